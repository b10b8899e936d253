"""The mjcf part of ``./run demo``: any machine from its MuJoCo model, on the shipped bags.

The bags of ``plants/mjcf/data/`` were recorded over DDS from this plant's nodes
(``cable_sim_node --plant mjcf``, ``pd_feedforward``, ``payload_estimator``, ``cablelab record``;
``data/make_bags.py`` regenerates them), each simulator carrying an effect its bag's description
lacks (:data:`SHIPPED`, the plant README's table). For each bag, from the bag alone (the model
XML travels in ``/plant_description``):

1. ``compare``: the nominal model (MuJoCo's inverse dynamics of the described model) against the
   measured joint forces: in-sample NRMSE;
2. ``diagnose``: the hidden effect ranks first and significant; held-out NRMSE nominal -> with it;
3. ``identify`` with it: its parameters against the simulated truth, and the NRMSE after.

The arm's diagnosis is also written as a ``cablelab report`` (``<out>/mjcf/report/index.html``);
``<out>/mjcf/mjcf.html`` holds the table. ``--quick`` analyses the arm and the gantry crane
(``--mjcf-bags`` chooses).
"""
from __future__ import annotations

import html
import shutil
import time
from dataclasses import dataclass
from pathlib import Path

from ...demo import DemoPart, PartResult, log

DATA = Path(__file__).resolve().parent / "data"


@dataclass(frozen=True)
class Shipped:
    """A shipped bag's claim: what the simulator had that the description lacks.

    Args:
        title: the machine; hidden: the hidden effect in words; effect: its effect id;
        params: its parameters as ``identify`` names them, with the simulated values.
    """

    title: str
    hidden: str
    effect: str
    params: dict


#: the shipped bags (``plants/mjcf/data/<name>``) and their hidden effects
SHIPPED = {
    "arm3_payload": Shipped("three-joint arm (arm3.xml)", "1.5 kg payload on tool", "payload_mass",
                            {"m": 1.5}),
    "gantry_friction": Shipped("gantry crane (gantry.xml)",
                               "viscous friction on bridge (200 N s/m) and trolley (100 N s/m)",
                               "joint_viscous_friction", {"Fv[bridge]": 200.0, "Fv[trolley]": 100.0}),
    "cablecam_payload": Shipped("four-cable camera robot (cablecam.xml)", "2 kg camera on the carriage",
                                "payload_mass", {"m": 2.0}),
}
QUICK = ("arm3_payload", "gantry_friction")


def analyse_bag(bag: Path, folds: int, report_dir: Path | None = None) -> dict:
    """compare -> diagnose -> identify on one bag: ``{"nominal", "diagnosis", "identified"}``
    (the workbench's typed results) and the report's index when ``report_dir`` is given."""
    from ...report import build_report
    from ...workbench import build_model, compare, diagnose, identify_report, load

    plant, desc, ds = load(bag)
    nominal = build_model(plant, desc)
    cmp = compare(ds, nominal)
    # the report draws the greedy waterfall: the greedy steps for the bag it is written of
    d = diagnose(ds, nominal, plant.candidates(desc), folds=folds, greedy_mode=report_dir is not None)
    first = d.ranking[0].effect
    ident = identify_report(ds, build_model(plant, desc, [first]), folds=0)
    out = {"samples": ds.n, "nominal": cmp, "diagnosis": d, "identified": ident, "report": ""}
    if report_dir is not None:
        out["report"] = build_report(ds, d, report_dir, title=f"mjcf demo: {bag.name}").index
    return out


def _nrmse(channels: dict) -> float:
    vals = [m["nrmse"] for m in channels.values() if m.get("nrmse") is not None]
    return sum(vals) / len(vals) if vals else float("nan")


def rows_of(name: str, res: dict) -> list:
    """The table rows of one bag: ``[quantity, cablelab, simulated truth]``."""
    claim = SHIPPED[name]
    d, ident = res["diagnosis"], res["identified"]
    top = d.ranking[0]
    after = ident.quality.nrmse
    got = ", ".join(f"{k} = {ident.params[k]['value']:.4g} +- {ident.params[k]['stderr']:.2g}"
                    for k in claim.params if k in ident.params)
    return [
        [f"{name}: {claim.title}, samples", f"{res['samples']}", f"hidden: {claim.hidden}"],
        [f"{name}: diagnose: first effect", f"{top.effect}{' (significant)' if top.significant else ''}",
         claim.effect],
        [f"{name}: held-out NRMSE nominal -> + first",
         f"{100 * d.baseline_error:.1f} % -> {100 * top.error_after:.1f} %", "-"],
        [f"{name}: compare NRMSE nominal -> identify + first",
         f"{100 * _nrmse(res['nominal'].channels):.1f} % -> {100 * after:.1f} %", "-"],
        [f"{name}: identified", got or "-",
         ", ".join(f"{k} = {v:g}" for k, v in claim.params.items())],
    ]


def page(out: Path, rows: list, report: str) -> str:
    """``mjcf.html``: the table, linking the report."""
    table = "".join("<tr>" + "".join(f"<td>{html.escape(str(c))}</td>" for c in r) + "</tr>" for r in rows)
    link = (f"<p>Diagnosis report of the arm: <a href='{html.escape(str(Path(report).relative_to(out)))}'>"
            "report/index.html</a></p>") if report else ""
    path = out / "mjcf.html"
    path.write_text("<!DOCTYPE html><html><head><meta charset='utf-8'><title>mjcf demo</title></head>"
                    "<body style='font-family:sans-serif;max-width:1100px;margin:auto'>"
                    "<h1>Any machine from its MuJoCo model: shipped bags with hidden effects</h1>"
                    "<p>Each bag was recorded over DDS from cable_sim_node --plant mjcf, pd_feedforward "
                    "and cablelab record; the simulator had an effect the bag's description lacks.</p>"
                    "<table border=1 cellpadding=4><tr><th>quantity</th><th>cablelab</th>"
                    f"<th>simulated truth</th></tr>{table}</table>{link}</body></html>")
    return str(path)


def record(out: Path, a) -> list[Path]:
    """The chosen shipped bags, copied into ``out`` (the demo's outputs stay in one folder)."""
    out.mkdir(parents=True, exist_ok=True)
    bags = []
    for name in a.mjcf_bags.split(","):
        dst = out / name
        if dst.exists():
            shutil.rmtree(dst)
        shutil.copytree(DATA / name, dst)
        bags.append(dst)
    return bags


def analyse(out: Path, a, bags: list[Path]) -> PartResult:
    t0 = time.monotonic()
    rows, report = [], ""
    for k, bag in enumerate(bags):
        log(f"mjcf: compare, diagnose, identify {bag.name} ...")
        res = analyse_bag(bag, a.folds, out / "report" if k == 0 else None)
        report = report or res["report"]
        rows += rows_of(bag.name, res)
    return PartResult(rows=rows, bags=bags, report=report, page=page(out, rows, report),
                      first=rows[1][1].split()[0] if rows else "", seconds=time.monotonic() - t0)


def add_arguments(group) -> None:
    group.add_argument("--mjcf-bags", default=",".join(SHIPPED),
                       help=f"mjcf: shipped bags to analyse (comma-separated; {', '.join(SHIPPED)})")


def quick(a) -> None:
    """--quick: the arm and the gantry crane."""
    if a.mjcf_bags == ",".join(SHIPPED):
        a.mjcf_bags = ",".join(QUICK)


def _check(a) -> None:
    unknown = [n for n in a.mjcf_bags.split(",") if n not in SHIPPED]
    if unknown:
        from ...errors import CablelabError

        raise CablelabError(f"--mjcf-bags: unknown bag {unknown[0]!r} (shipped: {', '.join(SHIPPED)})")


def _record(out: Path, a) -> list[Path]:
    _check(a)
    return record(out, a)


DEMO = DemoPart(plant="mjcf", title="Any machine from its MuJoCo model (mjcf), hidden effects",
                order=25, add_arguments=add_arguments, record=_record, analyse=analyse, quick=quick,
                subdir="mjcf", how="shipped bags recorded over DDS (sim + controller + recorder), "
                                   "then the workbench")
