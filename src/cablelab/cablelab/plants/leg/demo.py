"""The leg section of ``./run demo``: data from the MuJoCo plant with the impact map and
a 2.7 N spring preload hidden; ``diagnose --greedy`` on 003's model without impact adds
``impact_restitution`` then ``spring_preload`` (error waterfall); the 003 Fig. 11 comparison of
apex height and time errors with and without the impact map; plots of the apex-to-apex return
map and of the residual around touch-down / lift-off.

Then the experiment-design loop, closed over DDS: low hops (4 mm, the apex controller on the
hybrid leg, offline) confound the preload F0 with the mass m when m is free; ``cablelab excite``
designs an apex-height schedule for (F0, m) from that recording; ``cable_sim_node --plant leg``
(2.7 N preload hidden) + ``payload_estimator`` + ``pd_feedforward -p reference_bag:=REF`` + the
recorder play it as separate processes (bags ``<out>/leg/low_hops``, ``<out>/leg/designed``,
reference ``<out>/leg/designed_ref``). On the recorded run ``diagnose`` with the mass fixed at
its weighed value (the description's, ``--fix m=``) ranks ``spring_preload`` first and brings F0
back; the table shows the condition numbers before and after (F0, m with m free; F0 against the
stance mass ``dm_f`` with m weighed) and the fits of F0 and m.
"""
from __future__ import annotations

import json
import math
from pathlib import Path

import numpy as np

from ...demo import DemoPart, PartResult

SCHEDULE = [(1.5, 0.30), (2.5, 0.35), (3.0, 0.30), (2.0, 0.35), (2.5, 0.30)]  # (T N m, P s)


def _law(block_s: float):
    def law(t, sim):
        T, P = SCHEDULE[min(int(t // block_s), len(SCHEDULE) - 1)]
        return T * math.sin(2 * math.pi * (t - sim.t_d) / P)
    return law


def run(out_dir: Path, quick: bool = False) -> dict:
    """Run the demo, write ``leg_demo.json`` and plots into ``out_dir``; returns the table rows."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    from ...workbench import build_model, diagnose, load
    from .description import leg_of
    from .hybrid import LegParams
    from .identify import apex_errors, record_from_trajectory, simulate_strides, stride_segments
    from .sim import simulate, write_bag
    from .strides import apexes

    out_dir = Path(out_dir)
    out_dir.mkdir(parents=True, exist_ok=True)
    desc_path = Path(__file__).parent / "data" / "leg.yaml"
    truth = LegParams(F0=2.7)
    block = 2.0 if quick else 4.0
    traj = simulate(truth, truth.z_td + 0.03, 0.0, block * len(SCHEDULE), _law(block))
    bag = out_dir / "leg_hidden_impact_preload"
    write_bag(bag, traj, desc_path.read_text(), overwrite=True)
    plant, desc, ds = load(bag)
    # the leg is weighed (003: 1.62 kg on a scale): its mass is known. With m free, a spring
    # preload F_0 and a stance inertia m - F_0 / g (phase_effective_mass) are the same stance force
    res = diagnose(ds, build_model(plant, desc, fixed={"m": leg_of(desc).mass}), plant.candidates(desc),
                   greedy_mode=True).to_json()
    rows = []
    for s in res["greedy"]:
        rows.append({"step": s["added"] or "003 model without impact (baseline)", "cv_error": s["error"]})
    final = res["greedy"][-1]["params"]
    m = final["m"]
    ident = {"m": m, "d_s": final["d_s"], "d_f": final["d_f"]}
    if "c_td" in final:
        ident.update(beta_td=1 - final["c_td"] / m, beta_lo=1 - final["c_lo"] / m)
    if "F0" in final:
        ident["F0"] = final["F0"]

    # 003 Fig. 11: single strides of the demo data simulated with and without the impact map
    model = LegParams(**{k: v for k, v in ident.items() if k in ("m", "d_s", "d_f", "beta_td", "beta_lo", "F0")})
    segs = stride_segments([record_from_trajectory(traj)])
    sims = simulate_strides(segs, [model, model.no_impact()])
    full, none = apex_errors(segs, sims[0]), apex_errors(segs, sims[1])
    fig11 = {"strides": len(segs),
             "apex_height_mae_mm": {"with_impact": 1e3 * float(np.mean(full["height"])),
                                    "without_impact": 1e3 * float(np.mean(none["height"]))},
             "apex_time_mae_ms": {"with_impact": 1e3 * float(np.mean(full["time"])),
                                  "without_impact": 1e3 * float(np.mean(none["time"]))},
             "paper": "003 Fig. 11: box plots only (no numbers, spec E10); with impact < without"}

    # plots: error waterfall, apex return map, residual around the transitions
    fig, ax = plt.subplots(1, 3, figsize=(15, 4))
    ax[0].bar(range(len(rows)), [r["cv_error"] for r in rows])
    ax[0].set_xticks(range(len(rows)), [r["step"].split(" (")[0] for r in rows], rotation=20, fontsize=7)
    ax[0].set_ylabel("CV error (NRMSE)")
    ax[0].set_title("greedy diagnose waterfall")
    ap = apexes(traj.t, traj.z_meas, traj.contact)
    h = 1e3 * (ap[:, 1] - truth.z_td)
    ax[1].plot(h[:-1], h[1:], "o", ms=3)
    lim = [min(h.min(), 0), h.max() * 1.05]
    ax[1].plot(lim, lim, "k:", lw=0.8)
    ax[1].set_xlabel("apex n above z_td (mm)")
    ax[1].set_ylabel("apex n+1 (mm)")
    ax[1].set_title("apex-to-apex return map")
    win = np.arange(-40, 41)
    for j, (lab, sim) in enumerate((("with impact", sims[0]), ("without impact", sims[1]))):
        err = []
        for k, sg in enumerate(segs):
            e = sim[k, : sg.n, 1] - sg.zd
            idx = np.flatnonzero(np.diff(sg.contact) != 0) + 1
            for i in idx:
                if 40 <= i < sg.n - 41:
                    err.append(e[i + win])
        if err:
            ax[2].plot(win, 1e3 * np.mean(np.abs(err), axis=0), label=lab)
    ax[2].set_xlabel("samples from a contact edge (ms)")
    ax[2].set_ylabel("mean |zdot residual| (mm/s)")
    ax[2].set_title("residual around transitions")
    ax[2].legend()
    fig.tight_layout()
    fig.savefig(out_dir / "leg_demo.png", dpi=110)
    plt.close(fig)
    out = {"waterfall": rows, "identified": ident, "truth": {"beta_td": truth.beta_td, "beta_lo": truth.beta_lo,
                                                            "F0": truth.F0, "m": truth.m},
           "fig11": fig11, "plot": str(out_dir / "leg_demo.png")}
    (out_dir / "leg_demo.json").write_text(json.dumps(out, indent=2))
    out["bag"] = str(bag)
    return out


#: the loop's hidden preload (N) and the apex height of its low hops above z_td (m)
LOOP_F0, LOW_HOPS = 2.7, 0.004
#: the pair the design separates (m free), and the preload against the stance mass (m weighed)
LOOP_PARAMS, WEIGHED_PAIR = ("F0", "m"), ("F0", "dm_f")


def run_over_dds(bag: Path, logs: Path, duration: float, domain: int, reference: Path) -> Path:
    """``cable_sim_node --plant leg`` (preload :data:`LOOP_F0` hidden, lock-step: every 1 ms state
    waits for the torque answering it) + ``payload_estimator`` + ``pd_feedforward`` playing
    ``reference`` (``reference_bag``) + the recorder, over DDS into ``bag`` for ``duration``
    simulated s. (In real time on a loaded machine the chain's delay outlasts a low hop's 40 ms
    flight: the stance torque runs on into the flight and the next stance, and the recording is
    no longer the apex controller's hopping.)"""
    import sys
    import time

    from ...demo import log
    from ...ros.launch import Launcher
    from ...ros.sim_progress import SimProgress
    from . import topics

    t0 = time.monotonic()
    with Launcher(domain_id=domain, log_dir=logs) as launch:
        launch.start("recorder", [sys.executable, "-m", "cablelab.cli", "record", "--plant", "leg",
                                  "-o", bag, "--overwrite", "--quiet"])
        launch.node("estimator", "payload_estimator", "leg", {})
        launch.node("controller", "pd_feedforward", "leg", {"reference_bag": str(reference)})
        # every reader discovered before the simulator starts its clock
        launch.wait_for_subscribers([topics.JOINT_STATES, topics.CONTACT, topics.HOP_ESTIMATE,
                                     topics.REFERENCE, topics.EFFORT_COMMANDS],
                                    timeout=90, node_name="cablelab_recorder")
        launch.wait_for_subscribers([topics.JOINT_STATES, topics.CONTACT], timeout=90,
                                    node_name="payload_estimator")
        launch.wait_for_subscribers([topics.HOP_ESTIMATE], timeout=90, node_name="pd_feedforward")
        # time starts once the recorder and the estimator have the start state (start gate)
        launch.node("sim", "cable_sim_node", "leg", {"preload": LOOP_F0, "lockstep": True,
                                                     "wait_for_subscribers": 2})
        with SimProgress(launch.probe(), duration, "leg designed") as bar:
            bar.wait_for(launch, duration, "leg", logs)
        time.sleep(1.0)                     # let the recorder take the last messages
        launch.stop_all_checked("leg", logs)
    log(f"leg: recorded {bag} in {time.monotonic() - t0:.0f} s")
    return bag


def close_loop(out_dir: Path, *, low_s: float, designed_s: float, domain: int, max_iter: int) -> dict:
    """The loop up to the recordings: the low hops (offline, hybrid leg under the apex controller,
    preload hidden), ``cablelab excite`` for :data:`LOOP_PARAMS` on them, the designed schedule
    played over DDS (:func:`run_over_dds`). Returns the paths and the design's numbers."""
    from ...demo import log
    from ...description import load_description
    from ...excite import design, get_exciter, write_reference
    from .dataset import dataset_from_arrays
    from .excite import closed_loop
    from .hybrid import LegParams
    from .sim import write_bag

    desc_text = (Path(__file__).parent / "data" / "leg.yaml").read_text()
    desc = load_description(desc_text)
    nominal = LegParams()
    low, ref = out_dir / "low_hops", out_dir / "designed_ref"
    log(f"leg: low hops ({1e3 * LOW_HOPS:g} mm, {low_s:g} s, offline) with a hidden {LOOP_F0} N preload ...")
    tr = closed_loop(nominal.replace(F0=LOOP_F0), nominal.z_td + LOW_HOPS, low_s, controller_params=nominal)
    write_bag(low, tr, desc_text, overwrite=True)
    ds0 = dataset_from_arrays(tr.t, tr.z_meas, tr.contact, tr.tau, desc)
    log(f"leg: cablelab excite --params {','.join(LOOP_PARAMS)} --duration {designed_s:g} ...")
    d = design("leg", desc, LOOP_PARAMS, duration=designed_s, before_ds=ds0, max_iter=max_iter)
    write_reference(ref, d, get_exciter("leg"), desc_text, overwrite=True)
    log(f"leg: excite's condition number {d.condition_before:.3g} -> {d.condition_after:.3g} "
        f"({d.seconds:.1f} s); pd_feedforward -p reference_bag:={ref} over DDS ...")
    designed = run_over_dds(out_dir / "designed", out_dir / "logs_designed", designed_s, domain, ref)
    return {"low_hops": str(low), "designed": str(designed), "reference": str(ref),
            "condition_before": d.condition_before, "condition_after": d.condition_after,
            "design_s": d.seconds, "duration_s": designed_s}


def loop_fit(bag_dir) -> dict:
    """On one bag: the fit with m free (003's model + impacts + preload: F0, m, the condition
    number of (F0, m)) and ``diagnose`` with m fixed at the weighed (description) mass (the first
    effect, its significance, rivals, F0; the condition number of (F0, dm_f))."""
    from ...excite import condition
    from ...fit import identify
    from ...workbench import build_model, diagnose, load
    from .description import leg_of

    plant, desc, ds = load(bag_dir)
    free = build_model(plant, desc, ["impact_restitution", "spring_preload"])
    fit = identify(free, ds)
    weighed = {"m": leg_of(desc).mass}
    both = build_model(plant, desc, ["impact_restitution", "spring_preload", "phase_effective_mass"],
                       fixed=weighed)
    d = diagnose(ds, build_model(plant, desc, ["impact_restitution"], fixed=weighed),
                 plant.candidates(desc)).to_json()
    first = d["ranking"][0]
    pre = next((r for r in d["ranking"] if r["effect"] == "spring_preload"), {"params": {}})
    return {"F0_free": float(fit.params["F0"]), "m_free": float(fit.params["m"]),
            "cond_free": condition(free, ds, LOOP_PARAMS), "cond_weighed": condition(both, ds, WEIGHED_PAIR),
            "first": first["effect"], "significant": bool(first["significant"]),
            "ambiguous_with": first.get("ambiguous_with") or [], "F0": pre["params"].get("F0", float("nan")),
            "error": (d["baseline"]["error"], first["error_after"]), "weighed_m": weighed["m"], "n": ds.n}


def loop_rows(loop: dict) -> list:
    """The loop's table rows: condition numbers, fits and the diagnosis, low hops -> designed."""
    a, b = loop_fit(loop["low_hops"]), loop_fit(loop["designed"])
    loop["fits"] = {"low_hops": a, "designed": b}
    amb = f", ambiguous with {', '.join(b['ambiguous_with'])}" if b["ambiguous_with"] else ""
    return [
        ["loop: excite's condition number of (F0, m), low hops -> designed schedule",
         f"{loop['condition_before']:.3g} -> {loop['condition_after']:.3g} (designed in {loop['design_s']:.1f} s)",
         "-"],
        ["loop: condition number of (F0, m) in the fitted model, m free, low hops -> DDS run",
         f"{a['cond_free']:.3g} -> {b['cond_free']:.3g}", "-"],
        ["loop: condition number of (F0, dm_f), m weighed, low hops -> DDS run",
         f"{a['cond_weighed']:.3g} -> {b['cond_weighed']:.3g}", "-"],
        [f"loop: F0 (N) / m (kg) with m free, low hops -> DDS run (truth {LOOP_F0} / {b['weighed_m']:g})",
         f"{a['F0_free']:.2f} / {a['m_free']:.3f} -> {b['F0_free']:.2f} / {b['m_free']:.3f}", "hidden"],
        [f"loop: diagnose on the DDS run, m weighed ({b['weighed_m']:g} kg): first effect",
         f"{b['first']} ({'significant' if b['significant'] else 'not significant'}{amb})", "spring_preload"],
        [f"loop: held-out error -> + first; F0 (N, truth {LOOP_F0})",
         f"{100 * b['error'][0]:.1f} % -> {100 * b['error'][1]:.1f} %; {b['F0']:.2f} "
         f"({100 * (b['F0'] / LOOP_F0 - 1):+.1f} %)", "hidden"],
    ]


def _page(out_dir: Path, rows: list) -> str:
    """``leg.html``: the table and the plots."""
    import html

    table = "".join("<tr>" + "".join(f"<td>{html.escape(str(c))}</td>" for c in r) + "</tr>" for r in rows)
    path = out_dir / "leg.html"
    path.write_text("<!DOCTYPE html><html><head><meta charset='utf-8'><title>hopping leg demo</title>"
                    "</head><body style='font-family:sans-serif;max-width:1100px;margin:auto'>"
                    "<h1>Parallel-elastic hopping leg (003): impact map and preload hidden</h1>"
                    "<table border=1 cellpadding=4><tr><th>quantity</th><th>cablelab</th><th>003</th>"
                    f"</tr>{table}</table><img src='leg_demo.png' style='max-width:100%'></body></html>")
    return str(path)


def _analyse(out_dir: Path, args, res: dict) -> PartResult:
    """The demo table: waterfall, identified impact parameters, 003 Fig. 11 apex errors."""
    w, ident, truth, f11 = res["waterfall"], res["identified"], res["truth"], res["fig11"]
    rows = [["diagnose --greedy waterfall (held-out error)",
             " -> ".join(f"{r['step'].split(' (')[0]} {100 * r['cv_error']:.1f} %" for r in w),
             "impact_restitution, spring_preload (hidden)"],
            ["beta_td / beta_lo (truth)",
             f"{ident.get('beta_td', float('nan')):.3f} / {ident.get('beta_lo', float('nan')):.3f} "
             f"({truth['beta_td']:.3f} / {truth['beta_lo']:.3f})", "Table 2"],
            ["spring preload F0 (N, truth 2.7)", f"{ident.get('F0', float('nan')):.2f}", "hidden"],
            ["apex height MAE with / without impact (mm)",
             f"{f11['apex_height_mae_mm']['with_impact']:.2f} / {f11['apex_height_mae_mm']['without_impact']:.2f}",
             "Fig. 11: with < without"],
            ["apex time MAE with / without impact (ms)",
             f"{f11['apex_time_mae_ms']['with_impact']:.1f} / {f11['apex_time_mae_ms']['without_impact']:.1f}",
             "Fig. 11: with < without"]]
    bags = [res["bag"]]
    loop = res.get("loop")
    if loop:
        rows += loop_rows(loop)
        bags += [loop["low_hops"], loop["designed"]]
        (Path(out_dir) / "leg_loop.json").write_text(json.dumps(loop, indent=2))
    return PartResult(rows=rows, bags=bags, page=_page(Path(out_dir), rows),
                      first=w[1]["step"] if len(w) > 1 else "")


def add_arguments(group) -> None:
    group.add_argument("--leg-loop", type=float, nargs=2, default=(30.0, 20.0), metavar=("S1", "S2"),
                       help="leg: simulated s of the low hops (offline) and of the designed schedule "
                            "played over DDS in lock-step at 1 kHz (preload vs mass); 0 0 skips that step")


def quick(a) -> None:
    """--quick: 10 s of low hops and the shortest designed schedule (8 s: two 2 s fades and 4 s
    between), fewer design iterations."""
    a.leg_loop = (min(a.leg_loop[0], 10.0), min(a.leg_loop[1], 8.0))


def _record(out: Path, a) -> dict:
    from ...ros.launch import unique_domain_id

    res = run(out, quick=a.quick)
    s1, s2 = a.leg_loop
    if s1 > 0 and s2 > 0:
        res["loop"] = close_loop(Path(out), low_s=s1, designed_s=s2, domain=unique_domain_id(4),
                                 max_iter=3 if a.quick else 20)
    return res


DEMO = DemoPart(plant="leg", title="Hopping leg (003), impact map and preload hidden", order=40,
                add_arguments=add_arguments, record=_record, analyse=_analyse, quick=quick,
                subdir="leg", how="MuJoCo hybrid-plant data (offline); the designed schedule over DDS "
                                  "(sim + estimator + controller + recorder); then the workbench")
