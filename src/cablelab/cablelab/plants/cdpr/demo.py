"""The CDPR part of ``./run demo``: CAROCA (001) through real nodes, then the analysis.

1. Two closed-loop runs of the pick-and-place test trajectory (001 sec. II-C, A -> E -> A) with
   the heaviest payload (366 + 249 kg, CoM offset along x_p as 001 Fig. 11): simulator,
   payload estimator, PD/PDFF controller and recorder as separate processes over DDS (unique
   ROS_DOMAIN_ID, simulator in lock-step as fast as possible). Bags: ``bags/demo/cdpr_pdff`` and
   ``bags/demo/cdpr_pd``.
2. ``cablelab estimate`` on the PDFF bag: Model I vs Model II with dynamometers (001 Table I),
   motor torques raw vs friction compensated (001 Table II); PD vs PDFF z error (001 Fig. 15).
3. ``cablelab diagnose`` starting from Model I (pulleys unknown), and from motor torques without
   friction: which effect is missing; ``cablelab report`` (HTML) of the first, plus a CDPR page
   with the mass estimates and the z errors (``bags/demo/report/``).
"""
from __future__ import annotations

import sys
import time
from pathlib import Path

import numpy as np

from ...demo import DemoPart, PartResult, log
from . import topics

PAYLOAD = 249.0
TRUE_MASS = 366.0 + PAYLOAD
PAPER = {  # 001 Tables I-II and Fig. 15, MP + M2 (615 kg)
    "model1_err": 4.5, "model2_err": 0.7, "model1_std": 6.2, "model2_std": 4.3,
    "raw_std": 78.5, "friction_std": 31.3, "dyn_std": 4.3, "pd_z": 20.0, "pdff_z": 5.0,
}


def run_nodes(out: Path, name: str, feedforward: bool, duration: float, domain: int) -> Path:
    """One closed-loop run through the four node processes; returns the bag directory."""
    from ...ros.launch import Launcher

    bag = out / name
    logs = out / "logs" / name
    with Launcher(domain_id=domain, log_dir=logs) as launch:
        launch.start("recorder", [sys.executable, "-m", "cablelab.cli", "record", "--plant", "cdpr",
                                  "-o", bag, "--overwrite", "--quiet"])
        launch.node("estimator", "payload_estimator", "cdpr", {"model": "II", "tensions": "dynamometer"})
        # lock-step chain sim -> estimator -> controller: each state waits (up to 5 s wall) for the
        # live estimate of its own stamp, so a loaded machine cannot starve the feedforward
        launch.node("controller", "pd_feedforward", "cdpr",
                    {"feedforward": feedforward, "estimate_wait": 5.0 if feedforward else 0.0})
        # every reader discovered before time starts (the estimator reads /cdpr/cable_tensions,
        # not /cdpr/joint_states: waiting there for 3 subscribers cost 60 s of timeout per run)
        launch.wait_for_subscribers([topics.JOINT_STATES, topics.CABLE_TENSIONS, topics.REFERENCE,
                                     topics.PAYLOAD_ESTIMATE, topics.EFFORT_COMMANDS],
                                    timeout=90, node_name="cablelab_recorder")
        launch.wait_for_subscribers([topics.CABLE_TENSIONS, topics.REFERENCE], timeout=90,
                                    node_name="payload_estimator")
        launch.wait_for_subscribers([topics.JOINT_STATES, topics.REFERENCE], timeout=90,
                                    node_name="pd_feedforward")
        launch.node("sim", "cable_sim_node", "cdpr", {"real_time": False, "payload_mass": PAYLOAD,
                                                      "duration": duration, "settle": 1.0,
                                                      "wait_for_subscribers": 2})  # recorder, controller
        t0 = time.monotonic()
        from ...ros.sim_progress import SimProgress

        with SimProgress(launch.probe(), duration, f"cdpr {name}") as bar:
            while launch.procs["sim"].alive():
                bar.poll(0.5)                # simulated time from /clock: rate and ETA from it
                launch.check_alive()
                if time.monotonic() - t0 > 20 * duration + 60:
                    raise RuntimeError(f"{name}: simulator did not finish; logs in {logs}")
        time.sleep(1.5)                     # let the recorder take the last messages
        codes = launch.stop_all()
    bad = {k: v for k, v in codes.items() if v != 0}
    if bad:
        raise RuntimeError(f"{name}: processes exited with {bad}; logs in {logs}")
    log(f"{name}: recorded {bag} in {time.monotonic() - t0:.0f} s")
    return bag


def z_error(bag: Path) -> tuple[np.ndarray, np.ndarray]:
    """(t, z_true - z_ref) of a run, m (after the 1 s settle)."""
    from ...bags import open_bag

    b = open_bag(bag)
    gt = b.pose(topics.GROUND_TRUTH_POSE)
    ref = b.multidof_trajectory(topics.REFERENCE)
    zr = np.interp(gt.t, ref.t, ref.position[:, 2])
    sel = gt.t > 1.0
    return gt.t[sel] - 1.0, gt.position[sel, 2] - zr[sel]


def cdpr_page(out: Path, bag: Path, pd_bag: Path | None, rows: list, report_index: str) -> str:
    """A small HTML page with the 001 reproductions (mass estimates, Fig. 15 z errors)."""
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    from .estimate import estimate_bag

    rep = out / "report"
    rep.mkdir(parents=True, exist_ok=True)
    fig, ax = plt.subplots(2, 1, figsize=(9, 7), sharex=True)
    for label, kw in (("Model I, dynamometers", {"effects": (), "description": _model1(bag)}),
                      ("Model II, dynamometers", {}),
                      ("Model II, motor torques raw", {"tensions": "motor"}),
                      ("Model II, motor torques - friction", {"tensions": "motor", "effects":
                       ("winch_coulomb_friction", "winch_viscous_friction")})):
        e = estimate_bag(bag, kw.pop("description", None), _options(kw.pop("tensions", "dynamometer")), **kw)
        ax[0].plot(e.t - 1.0, e.mass, lw=0.8, label=label)     # t = 0 at the end of the 1 s settle
    ax[0].axhline(TRUE_MASS, color="k", ls="--", lw=1, label="true 615 kg")
    ax[0].set_ylabel("estimated mass (kg)")
    ax[0].set_ylim(TRUE_MASS - 230, TRUE_MASS + 150)       # room for the legend under the curves
    ax[0].legend(fontsize=8, ncol=3, loc="lower center")
    ax[0].set_title("001 Fig. 7 / Fig. 13: mass of MP + M2 along the test trajectory")
    t, ez = z_error(bag)
    ax[1].plot(t, 1000 * ez, label="PDFF (live mass feedforward)")
    if pd_bag is not None:
        t2, ez2 = z_error(pd_bag)
        ax[1].plot(t2, 1000 * ez2, label="PD (no feedforward)")
    ax[1].axhline(-5, color="gray", ls=":", lw=1)
    ax[1].axhline(5, color="gray", ls=":", lw=1)
    ax[1].set_ylabel("z error (mm)")
    ax[1].set_xlabel("t (s)")
    ax[1].legend(fontsize=8)
    ax[1].set_title("001 Fig. 15 (right): platform z error, 615 kg")
    fig.tight_layout()
    fig.savefig(rep / "cdpr_001.png", dpi=110)
    plt.close(fig)
    table = "".join(f"<tr><td>{r[0]}</td><td>{r[1]}</td><td>{r[2]}</td></tr>" for r in rows)
    html = (f"<html><head><meta charset='utf-8'><title>CAROCA demo</title></head><body>"
            f"<h1>CAROCA (001) through real nodes</h1><p>Bag: {bag}</p>"
            f"<table border=1 cellpadding=4><tr><th>quantity</th><th>cablelab</th><th>001</th></tr>"
            f"{table}</table><img src='cdpr_001.png'>"
            f"<p>Diagnosis report (Model I baseline, dynamometers): <a href='index.html'>index.html</a></p>"
            f"</body></html>")
    path = rep / "cdpr.html"
    path.write_text(html)
    return str(path)


def _options(tensions: str):
    """The estimate's options with the tension source ``tensions`` (the CDPR's ``--tensions``)."""
    from ...plant_interface import DatasetOptions
    from .options import CdprOptions

    return DatasetOptions(plant=CdprOptions(tensions=tensions))


def _model1(bag: Path):
    """The bag's description without the pulley radius (Model I)."""
    from ...bags import open_bag
    from .sim import without_pulley_radius

    return without_pulley_radius(open_bag(bag).description)


def cdpr_runs(out: Path, a) -> tuple[Path, Path | None]:
    """Step 1 for CAROCA: the PDFF and PD runs over DDS; returns their bags."""
    from ...ros.launch import unique_domain_id

    out.mkdir(parents=True, exist_ok=True)
    log("CAROCA (001): 8 cables, 2-DoF pulleys r = 0.15 m, 366 kg platform + 249 kg payload")
    pdff = run_nodes(out, "cdpr_pdff", True, a.duration, unique_domain_id(1))
    pd = None if a.skip_pd else run_nodes(out, "cdpr_pd", False, min(a.duration, 31.0),
                                          unique_domain_id(2))
    return pdff, pd


def cdpr_analysis(out: Path, a, runs: tuple) -> PartResult:
    """Steps 2-3 for CAROCA on the runs of :func:`cdpr_runs`; the table rows, bags, reports."""
    pdff, pd = runs
    from .estimate import estimate_bag

    t0 = time.monotonic()
    log("estimating (cablelab estimate) ...")
    m1 = estimate_bag(pdff, _model1(pdff)).summary()
    m2 = estimate_bag(pdff).summary()
    raw = estimate_bag(pdff, options=_options("motor")).summary()
    fr = estimate_bag(pdff, options=_options("motor"),
                      effects=("winch_coulomb_friction", "winch_viscous_friction")).summary()
    _, ez = z_error(pdff)
    ez_pd = z_error(pd)[1] if pd is not None else None

    log("diagnosing (cablelab diagnose) ...")
    from ...workbench import build_model, diagnose, load
    from ...registry import get_plant
    plant = get_plant("cdpr")
    _, desc, ds = load(pdff, None, {"tensions": "dynamometer"})
    base1 = build_model(plant, desc, (), ("cdpr_gravity",))
    _, _, dsm = load(pdff, None, {"tensions": "motor"})
    d2 = diagnose(dsm, build_model(plant, desc), plant.candidates(desc), folds=a.folds)

    log("writing the report (cablelab report) ...")
    from ...report import build_report
    d1 = diagnose(ds, base1, plant.candidates(desc), folds=a.folds, greedy_mode=True)
    rep = build_report(ds, d1, out / "report", title="CAROCA demo: dynamometers, Model I baseline")
    steps = d1.greedy                   # the report's greedy waterfall

    def err(s):
        return 100 * (s["mass"]["mean"] - TRUE_MASS) / TRUE_MASS

    rows = [
        ["mass error, Model I, dynamometers (%)", f"{err(m1):+.2f}", f"-{PAPER['model1_err']}"],
        ["mass error, Model II, dynamometers (%)", f"{err(m2):+.2f}", f"+{PAPER['model2_err']}"],
        ["mass std, Model I / II (kg)", f"{m1['mass']['std']:.1f} / {m2['mass']['std']:.1f}",
         f"{PAPER['model1_std']} / {PAPER['model2_std']}"],
        ["mass std, motor raw / - friction / dyn (kg)",
         f"{raw['mass']['std']:.1f} / {fr['mass']['std']:.1f} / {m2['mass']['std']:.1f}",
         f"{PAPER['raw_std']} / {PAPER['friction_std']} / {PAPER['dyn_std']}"],
        ["CoM x_G, y_G (mm), Model II (true 60.7, 0)",
         f"{1000 * m2['com']['x']:.1f}, {1000 * m2['com']['y']:.1f}", "offset along x_p (Fig. 10)"],
        ["max |z error| PD / PDFF (mm)",
         f"{'-' if ez_pd is None else f'{1000 * np.abs(ez_pd).max():.1f}'} / {1000 * np.abs(ez).max():.1f}",
         f"~{PAPER['pd_z']:.0f} / < {PAPER['pdff_z']:.0f}"],
        ["diagnose, Model I + dynamometers: first effect", d1.ranking[0].effect, "pulleys (sec. V-A)"],
        ["diagnose, motor torques: first effect", d2.ranking[0].effect, "friction (eq. 15)"],
        ["waterfall, Model I + dynamometers (held-out NRMSE)",
         " -> ".join([f"nominal {100 * steps[0].error:.1f} %"]
                     + [f"{s.added} {100 * s.error:.1f} %" for s in steps[1:]]),
         "pulleys, then m a (eq. 10)"],
        ["m_a of platform_inertia (kg, true 615)",
         f"{steps[-1].params['m_a']:.1f}" if "m_a" in steps[-1].params else "not added", "-"],
    ]
    page = cdpr_page(out, pdff, pd, rows, rep.index)
    return PartResult(rows=rows, bags=[b for b in (pdff, pd) if b is not None], report=rep.index,
                      page=page, first=d1.ranking[0].effect, seconds=time.monotonic() - t0)




def add_arguments(group) -> None:
    group.add_argument("--duration", type=float, default=61.0, help="CDPR: simulated s of the PDFF run")
    group.add_argument("--skip-pd", action="store_true", help="CDPR: only the PDFF run")


def quick(a) -> None:
    """--quick: a 12 s PDFF run only."""
    a.duration, a.skip_pd = min(a.duration, 12.0), True


DEMO = DemoPart(plant="cdpr", title="CAROCA CDPR (001), payload M2, 615 kg", order=10,
                add_arguments=add_arguments, record=cdpr_runs, analyse=cdpr_analysis, quick=quick,
                subdir="")
