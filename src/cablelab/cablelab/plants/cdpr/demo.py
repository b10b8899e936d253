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
4. The loop closed for hidden dynamometer offsets (``tension_sensor_offset``): the lift at the
   pick point (A -> B, the pick-and-place's first 6 s, offline MuJoCo CAROCA with 001's payload
   M1 and eight hidden offsets) leaves the offsets confounded with the mass and the first moments
   (W b nearly constant along a vertical lift, like the weight); ``cablelab excite`` designs a
   platform motion for them from that recording, starting at A where the simulator starts;
   ``pd_feedforward -p reference_bag:=REF`` plays it to ``cable_sim_node`` (same payload, offsets
   hidden through ``tension_bias``) over DDS with the estimator and the recorder; the fit on that
   run separates them and brings the offsets, the mass and the centre of mass back. Bags:
   ``bags/demo/cdpr_lift``, ``bags/demo/cdpr_designed`` (reference ``bags/demo/cdpr_designed_ref``).
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


def run_nodes(out: Path, name: str, feedforward: bool, duration: float, domain: int, *,
              sim: dict | None = None, controller: dict | None = None) -> Path:
    """One closed-loop run through the four node processes; returns the bag directory. ``sim``
    and ``controller``: ROS parameters added to (or replacing) the runs' own."""
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
                    {"feedforward": feedforward, "estimate_wait": 5.0 if feedforward else 0.0,
                     **(controller or {})})
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
                                                      "wait_for_subscribers": 2,  # recorder, controller
                                                      **(sim or {})})
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


#: step 4: the dynamometer offsets the simulator hides (N, cables 1..8), its payload (001's M1,
#: CoM offset along x_p and y_p, below the platform) and dynamometer noise (N)
LOOP_BIAS = (40.0, -30.0, 25.0, -20.0, 35.0, -45.0, 15.0, -10.0)
LOOP_PAYLOAD, LOOP_COM, LOOP_NOISE = 122.0, (0.1, 0.05, -0.6), 2.0
#: the parameters to separate: the offsets from the mass and its first moments
LOOP_PARAMS = tuple(f"b[winch_{i}]" for i in range(1, 9)) + ("m", "mx", "my")
#: the first recording: the pick-and-place's first 6 s (the lift A -> B at the pick point), and
#: the designed one's length (s; a 60 s design did no better over DDS: largest offset error
#: 13.1 N, against 8.5-10.8 N in the 30 s runs)
LOOP_LIFT_S, LOOP_DESIGNED_S = 6.0, 30.0


def loop_truth():
    """The simulated CAROCA of step 4 (:class:`~cablelab.plants.cdpr.sim.CdprTruth`)."""
    from .sim import CdprTruth

    return CdprTruth(payload_mass=LOOP_PAYLOAD, payload_com=LOOP_COM, tension_bias=LOOP_BIAS,
                     tension_noise=LOOP_NOISE)


def loop_fit(bag_dir: Path):
    """Fit of Model II + ``tension_sensor_offset`` + ``platform_inertia`` (mass, first moments,
    sheave radius, offsets and accelerated mass free) on a bag: (dataset, identification, the
    diagnosis's confounded offsets (``identifiability.confounding``), condition number of
    :data:`LOOP_PARAMS` in that model (:func:`cablelab.excite.condition`))."""
    from ...diagnose.identifiability import confounding
    from ...excite import condition
    from ...fit import identify
    from ...workbench import build_model, load

    plant, desc, ds = load(bag_dir)
    model = build_model(plant, desc, ["tension_sensor_offset", "platform_inertia"])
    fit = identify(model, ds)
    return ds, fit, confounding(fit, list(LOOP_PARAMS[:8]))["confounded"], condition(model, ds, LOOP_PARAMS)


def close_loop(out: Path, *, designed_s: float, domain: int, max_iter: int = 30) -> dict:
    """Step 4 up to the recordings: the lift at the pick point (offline MuJoCo CAROCA, offsets
    hidden), ``cablelab excite`` on it for :data:`LOOP_PARAMS` (the reference starts where the
    simulator starts, at A), the designed reference played over DDS by ``pd_feedforward -p
    reference_bag:=REF`` to the simulator hiding the same offsets. Returns the paths and the
    design's condition numbers."""
    from ...excite import design, get_exciter, write_reference
    from .sim import default_description, simulate, write_run_bag

    desc = default_description()
    out.mkdir(parents=True, exist_ok=True)
    lift, ref = out / "cdpr_lift", out / "cdpr_designed_ref"
    log(f"cdpr: the lift at the pick point ({LOOP_LIFT_S:g} s, offline) with hidden dynamometer offsets "
        f"{', '.join(f'{b:g}' for b in LOOP_BIAS)} N and {LOOP_PAYLOAD:g} kg of payload ...")
    write_run_bag(simulate(desc, loop_truth(), duration=LOOP_LIFT_S), lift)
    ds0, _, conf, _ = loop_fit(lift)
    worst = conf[0] if conf else None
    log(f"cdpr: {len(conf)} confounded offset pairs"
        + (f" (worst {worst['param']} ~ {worst['with']} {worst['correlation']:+.3f})" if worst else "")
        + f": cablelab excite --params '{','.join(LOOP_PARAMS)}' --duration {designed_s:g} ...")
    d = design("cdpr", desc, LOOP_PARAMS, duration=designed_s, before_ds=ds0, max_iter=max_iter)
    write_reference(ref, d, get_exciter("cdpr"), desc.to_yaml(), overwrite=True)
    log(f"cdpr: excite's condition number (Model II + offsets) {d.condition_before:.4g} -> "
        f"{d.condition_after:.4g} "
        f"({d.seconds:.1f} s; {d.lead_in:g} s from A to the box's centre); pd_feedforward -p "
        f"reference_bag:={ref} over DDS ...")
    designed = run_nodes(out, "cdpr_designed", True, designed_s, domain,
                         sim={**loop_sim_params(), "publish_reference": False, **LOCKSTEP_PATIENCE["sim"]},
                         controller={"reference_bag": str(ref), **LOCKSTEP_PATIENCE["controller"]})
    return {"lift": lift, "designed": designed, "reference": ref, "design_s": d.seconds}


#: lock-step runs of step 4: simulated time stands still while a process waits for the CPU, so
#: wall-clock staleness means nothing there; with the defaults (0.5 s, 10 s) a busy machine can
#: make the controller skip a state as stale and the simulator step that state on its brakes (a
#: jolt of a few samples, slack cables, that pulls the fit of the offsets by 10 N)
LOCKSTEP_PATIENCE = {"sim": {"lockstep_timeout": 120.0},
                     "controller": {"reference_timeout": 120.0, "state_timeout": 120.0}}


def loop_sim_params() -> dict:
    """``cable_sim_node --plant cdpr`` parameters of :func:`loop_truth` (the hidden offsets)."""
    return {"payload_mass": LOOP_PAYLOAD, "payload_com": list(LOOP_COM), "tension_bias": list(LOOP_BIAS),
            "tension_noise": LOOP_NOISE}


def loop_rows(loop: dict) -> list:
    """Step 4's table rows: condition numbers, confounded pairs, parameters before and after."""
    from .sim import default_description

    _, f0, conf0, c0 = loop_fit(loop["lift"])
    _, f1, conf1, c1 = loop_fit(loop["designed"])
    truth = loop_truth().resolved(default_description())
    m, com = truth.total_mass, truth.total_com

    def offsets(f):
        return " / ".join(f"{f.params[p]:+.0f}" for p in LOOP_PARAMS[:8])

    def worst(f):
        return max(abs(f.params[p] - b) for p, b in zip(LOOP_PARAMS, LOOP_BIAS))

    def inertial(f):
        return f"{f.params['m']:.1f} ; {1000 * f.params['mx'] / f.params['m']:.0f}, " \
               f"{1000 * f.params['my'] / f.params['m']:.0f}"

    return [
        ["loop: condition number of the offsets + m, mx, my, lift -> designed", f"{c0:.3g} -> {c1:.3g}", "-"],
        ["loop: confounded offset pairs (|rho| >= 0.9), lift -> designed", f"{len(conf0)} -> {len(conf1)}", "-"],
        ["loop: dynamometer offsets b1..b8 (N), lift", offsets(f0), "sim " + " / ".join(f"{b:+g}" for b in LOOP_BIAS)],
        ["loop: same, designed reference over DDS", offsets(f1), "sim " + " / ".join(f"{b:+g}" for b in LOOP_BIAS)],
        ["loop: largest offset error (N), lift -> designed", f"{worst(f0):.1f} -> {worst(f1):.1f}", "-"],
        ["loop: mass (kg) ; x_G, y_G (mm), lift", inertial(f0),
         f"sim {m:g} ; {1000 * com[0]:.0f}, {1000 * com[1]:.0f}"],
        ["loop: same, designed reference over DDS", inertial(f1),
         f"sim {m:g} ; {1000 * com[0]:.0f}, {1000 * com[1]:.0f}"],
    ]


def cdpr_runs(out: Path, a) -> tuple:
    """Step 1 for CAROCA: the PDFF and PD runs over DDS, and step 4's recordings; returns their
    bags (and the loop's paths, or None)."""
    from ...ros.launch import unique_domain_id

    out.mkdir(parents=True, exist_ok=True)
    log("CAROCA (001): 8 cables, 2-DoF pulleys r = 0.15 m, 366 kg platform + 249 kg payload")
    pdff = run_nodes(out, "cdpr_pdff", True, a.duration, unique_domain_id(1))
    pd = None if a.skip_pd else run_nodes(out, "cdpr_pd", False, min(a.duration, 31.0),
                                          unique_domain_id(2))
    loop_s = LOOP_DESIGNED_S if a.cdpr_loop is None else a.cdpr_loop
    loop = close_loop(out, designed_s=loop_s, domain=unique_domain_id(4),
                      max_iter=a.cdpr_design_iter) if loop_s > 0 else None
    return pdff, pd, loop


def cdpr_analysis(out: Path, a, runs: tuple) -> PartResult:
    """Steps 2-3 for CAROCA on the runs of :func:`cdpr_runs`; the table rows, bags, reports."""
    pdff, pd, loop = runs
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
    if loop is not None:
        log("fitting the loop's recordings (offsets + payload) ...")
        rows += loop_rows(loop)
    page = cdpr_page(out, pdff, pd, rows, rep.index)
    bags = [pdff, pd] + ([loop["lift"], loop["designed"]] if loop is not None else [])
    return PartResult(rows=rows, bags=[b for b in bags if b is not None], report=rep.index,
                      page=page, first=d1.ranking[0].effect, seconds=time.monotonic() - t0)




def add_arguments(group) -> None:
    group.add_argument("--duration", type=float, default=61.0, help="CDPR: simulated s of the PDFF run")
    group.add_argument("--skip-pd", action="store_true", help="CDPR: only the PDFF run")
    group.add_argument("--cdpr-loop", type=float, default=None, metavar="S",
                       help=f"CDPR: simulated s of the designed recording that separates the hidden "
                            f"dynamometer offsets from the payload (default {LOOP_DESIGNED_S:g}; "
                            f"0 skips that step, as --quick does unless S is given)")
    group.add_argument("--cdpr-design-iter", type=int, default=30, metavar="N",
                       help="CDPR: optimiser iterations of that recording's design")


def quick(a) -> None:
    """--quick: a 12 s PDFF run only; the loop of step 4 only with ``--cdpr-loop S`` (it adds
    about a minute of wall time on a busy 2-core machine), then with 10 design
    iterations."""
    a.duration, a.skip_pd = min(a.duration, 12.0), True
    a.cdpr_loop = 0.0 if a.cdpr_loop is None else a.cdpr_loop
    a.cdpr_design_iter = min(a.cdpr_design_iter, 10)


DEMO = DemoPart(plant="cdpr", title="CAROCA CDPR (001), payload M2, 615 kg", order=10,
                add_arguments=add_arguments, record=cdpr_runs, analyse=cdpr_analysis, quick=quick,
                subdir="")
