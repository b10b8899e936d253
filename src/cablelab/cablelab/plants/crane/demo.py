"""The crane part of ``./run demo``: the boom crane of 002 on a hidden tilted base, through real nodes.

1. One closed-loop run: ``cable_sim_node --plant crane`` with a base tilted so that the slew joint
   carries -0.2 N m at rest (002 sec. 6.5; the description does not know it), 1 mm motion-capture
   noise and 1 % dropouts; ``payload_estimator`` (live swing angles from the two motion-capture
   poses, CONTRACT sec. 2); ``pd_feedforward`` (PD + gravity/acceleration feedforward, 002 sec.
   5.3.1) tracking its multi-sine excitation; the recorder. Bag: ``<out>/crane/run``.
2. Swing angles: the live estimate on ``/crane/swing_estimate`` and ``cablelab estimate`` (offline,
   002 sec. 5.1.3 conditioning) against ``/crane/ground_truth/swing``.
3. ``cablelab diagnose`` / ``report`` from the described crane (rigid body + counterbalance,
   l_c known): ``base_tilt`` should rank first and the fitted tilt should put 002's -0.2 N m back
   on the slew joint at rest; the waterfall, the ranking and the parameters with units are in
   ``<out>/crane/report/index.html``; ``<out>/crane/report/crane.html`` has the swing-angle plot.
4. The loop closed for a confounded pair: a recording that only slews (luff and rope held, hidden
   effort offsets, payload mass not weighed) leaves the hoist offset and the payload mass
   confounded (the payload's weight is a constant on the hoist, like the offset; the slew axis is
   vertical, so no weight reaches it); ``cablelab excite`` designs a reference for the pair from
   that recording; ``pd_feedforward -p reference_bag:=REF`` plays it to the simulated crane over
   DDS with the recorder; the fit on that run separates the pair and brings the offsets and the
   mass back. Bags: ``<out>/crane/confounded``, ``<out>/crane/designed`` (reference
   ``<out>/crane/designed_ref``).
"""
from __future__ import annotations

import sys
import time
from pathlib import Path

import numpy as np

from ...demo import DemoPart, PartResult, log
from . import topics
from .reference import slew_only

PAPER_REST_TORQUE = -0.2   # N m on the slew joint at rest at beta = 0.5 rad (002 sec. 6.5)
REST_LUFF = 0.5            # rad, the luff angle of that measurement (and of the sim's start)
SWING_NAMES = ("theta1", "theta2", "rope_length")


def tilt_for_rest_torque(first_moment: float, gravity: float, torque: float = PAPER_REST_TORQUE,
                         beta: float = REST_LUFF) -> float:
    """Base rotation about world x (rad) that loads the slew joint with ``torque`` (N m) at rest at
    alpha = 0, luff ``beta``: the ``base_tilt`` effect's rest torque cos(beta)(a sin(alpha) -
    b cos(alpha)) with b = K g sin(tilt) (002 sec. 6.5, K = boom-side first moment, kg m)."""
    return -float(np.arcsin(-torque / np.cos(beta) / first_moment / gravity))


def rest_torque(params: dict, first_moment: float, gravity: float, alpha: float = 0.0,
                beta: float = REST_LUFF) -> float:
    """Slew torque at rest (N m) implied by fitted ``base_tilt`` angles tilt_x, tilt_y (rad) of a
    crane with boom-side first moment K (kg m): cos(beta) K g (tilt_y sin(alpha) + tilt_x cos(alpha))
    (002 sec. 6.5; g_x = g tilt_y, g_y = -g tilt_x)."""
    return float(np.cos(beta) * first_moment * gravity
                 * (params["tilt_y"] * np.sin(alpha) + params["tilt_x"] * np.cos(alpha)))


def run_nodes(out: Path, duration: float, domain: int, tilt: float) -> Path:
    """Sim (tilted base) + estimator + controller + recorder over DDS for ``duration`` simulated s."""
    return run_over_dds(out / "run", out / "logs", duration, domain,
                        sim={"base_tilt": f"[{tilt!r}, 0.0]", "mocap_noise": 0.001, "mocap_dropout": 0.01},
                        controller={"reference_source": "excitation"}, estimator=True)


def run_over_dds(bag: Path, logs: Path, duration: float, domain: int, *, sim: dict, controller: dict,
                 estimator: bool) -> Path:
    """Sim + controller (+ estimator) + recorder over DDS into ``bag`` for ``duration`` simulated s;
    ``sim`` and ``controller`` are the nodes' ROS parameters."""
    from ...ros.launch import Launcher

    rate = 100.0
    with Launcher(domain_id=domain, log_dir=logs) as launch:
        launch.start("recorder", [sys.executable, "-m", "cablelab.cli", "record", "--plant", "crane",
                                  "-o", bag, "--overwrite", "--quiet"])
        if estimator:
            launch.node("estimator", "payload_estimator", "crane", {})
        launch.node("controller", "pd_feedforward", "crane", controller)
        launch.wait_for_subscribers([topics.JOINT_STATES, topics.EFFORT_COMMANDS, topics.SWING_TRUTH]
                                    + ([topics.SWING_ESTIMATE] if estimator else []),
                                    timeout=90, node_name="cablelab_recorder")
        launch.wait_for_subscribers([topics.JOINT_STATES], timeout=90, node_name="pd_feedforward")
        if estimator:
            launch.wait_for_subscribers([topics.TIP_POSE], timeout=90)
        launch.node("sim", "cable_sim_node", "crane", {
            "rate": rate, **sim, "wait_for_subscribers": 3 if estimator else 2})
        t0 = time.monotonic()
        from ...ros.sim_progress import SimProgress

        # simulated time from /clock (rate and ETA from it); no sample for 120 s wall is an error
        with SimProgress(launch.probe(), duration, "crane") as bar:
            bar.wait_for(launch, duration - 0.5 / rate, "crane", logs)
        time.sleep(1.0)
        launch.stop_all_checked("crane", logs)
    log(f"crane: recorded {bag} in {time.monotonic() - t0:.0f} s")
    return bag


def swing_errors(bag) -> dict:
    """Live ``/crane/swing_estimate`` vs ``/crane/ground_truth/swing`` at equal stamps:
    ``{"t", "est", "true", "rms"}`` (rad, rad, m)."""
    tru = bag.joint_state(topics.SWING_TRUTH, list(SWING_NAMES))
    est = bag.joint_state(topics.SWING_ESTIMATE, list(SWING_NAMES))
    idx = np.clip(np.searchsorted(tru.t, est.t), 0, tru.t.size - 1)
    ok = np.abs(tru.t[idx] - est.t) < 1e-6
    e, tr = est.position[ok], tru.position[idx[ok]]
    d = e - tr
    d[:, :2] = np.angle(np.exp(1j * d[:, :2]))        # the live estimate unwraps theta1
    return {"t": est.t[ok], "est": e, "true": tr, "matched": float(ok.mean()),
            "rms": {n: float(np.sqrt(np.nanmean(d[:, i] ** 2))) for i, n in enumerate(SWING_NAMES)},
            "range": {n: float(np.nanmax(np.abs(tr[:, i]))) for i, n in enumerate(SWING_NAMES)}}


def swing_plot(path: Path, sw: dict) -> None:
    """Live swing angles vs simulation truth (002 Fig. 6.1-style), and their error."""
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    t = sw["t"] - sw["t"][0]
    fig, ax = plt.subplots(3, 1, figsize=(9, 8), sharex=True)
    for i, (name, label) in enumerate((("theta1", "theta1, tangential"), ("theta2", "theta2, radial"))):
        ax[i].plot(t, np.degrees(sw["true"][:, i]), color="k", lw=1.4, label="ground truth")
        ax[i].plot(t, np.degrees(sw["est"][:, i]), color="tab:orange", lw=0.8, ls="--",
                   label="live estimate (payload_estimator)")
        ax[i].set_ylabel(f"{label} (deg)")
        ax[i].legend(fontsize=8, loc="upper right")
    err = np.degrees(np.angle(np.exp(1j * (sw["est"][:, :2] - sw["true"][:, :2]))))
    ax[2].plot(t, err[:, 0], lw=0.7, label=f"theta1 (RMS {np.degrees(sw['rms']['theta1']):.3f} deg)")
    ax[2].plot(t, err[:, 1], lw=0.7, label=f"theta2 (RMS {np.degrees(sw['rms']['theta2']):.3f} deg)")
    ax[2].set_ylabel("estimate - truth (deg)")
    ax[2].set_xlabel("t (s, from the first estimate)")
    ax[2].legend(fontsize=8, loc="upper right")
    ax[0].set_title("002 sec. 6.3: swing angles in the slewing frame, 1 mm motion-capture noise")
    fig.tight_layout()
    fig.savefig(path, dpi=100)
    plt.close(fig)


def crane_page(rep_dir: Path, bag: Path, rows: list, sw: dict) -> str:
    """``crane.html``: the demo's table vs 002 and the swing-angle plot, linking the report."""
    import html

    swing_plot(rep_dir / "crane_swing.png", sw)
    table = "".join("<tr>" + "".join(f"<td>{html.escape(str(c))}</td>" for c in r) + "</tr>" for r in rows)
    doc = ("<!DOCTYPE html><html><head><meta charset='utf-8'><title>Boom crane demo</title></head><body>"
           "<h1>Boom crane (002) on a hidden tilted base, through real nodes</h1>"
           f"<p>Bag: {html.escape(str(bag))}</p><table border=1 cellpadding=4>"
           "<tr><th>quantity</th><th>cablelab</th><th>002</th></tr>"
           f"{table}</table><img src='crane_swing.png'>"
           "<p>Diagnosis report (described crane, base tilt hidden): <a href='index.html'>index.html</a></p>"
           "</body></html>")
    path = rep_dir / "crane.html"
    path.write_text(doc)
    return str(path)


def record(out: Path, *, duration: float = 30.0, domain: int = 1) -> Path:
    """Step 1: the closed-loop run over DDS into ``out/run`` (the tilt hidden in the simulator)."""
    out.mkdir(parents=True, exist_ok=True)
    params = described_params()
    tilt = tilt_for_rest_torque(params.first_moment, params.gravity)
    log(f"boom crane (002): l_b = {params.boom_length} m, payload {params.payload_mass} kg, "
        f"counterbalance {params.counterbalance_mass} kg at {params.counterbalance_distance} m; "
        f"hidden base tilt {np.degrees(tilt):.2f} deg")
    return run_nodes(out, duration, domain, tilt)


def described_params():
    """:class:`CraneParams` of ``plants/crane/data/crane.yaml`` (the crane the simulator runs)."""
    from ...description import load_description
    from .model import CraneParams

    desc_file = Path(__file__).parent / "data" / "crane.yaml"
    return CraneParams.from_description(load_description(str(desc_file)))


#: step 4: the confounded pair, and the effort offsets [slew N m, luff N m, hoist N] the
#: simulator adds (hidden from the model, like the payload mass, which it fits)
LOOP_PARAMS = ("OF[hoist]", "m")
LOOP_OFFSET = (0.2, 0.0, 1.0)
LOOP_NOISE = (0.05, 0.05, 0.1)     # effort noise of the offline recording (N m, N m, N)


def loop_fit(bag_dir: Path):
    """Fit of the described crane + ``torque_sensor_offset`` on a bag, payload mass free (not
    weighed), boom and counterbalance as described: (dataset, identification, correlation of
    the pair, condition number of the pair in that model: :func:`cablelab.excite.condition`)."""
    from ...diagnose.identifiability import correlations
    from ...excite import condition
    from ...fit import identify
    from ...workbench import build_model, load

    plant, desc, ds = load(bag_dir)
    c = desc.crane
    model = build_model(plant, desc, ["torque_sensor_offset"], strict=True,
                        fixed={"m_b": c.boom_mass, "m_c": c.counterbalance.mass,
                               "l_c": c.counterbalance.distance})
    fit = identify(model, ds)
    names, corr = correlations(fit)
    a, b = (names.index(p) for p in LOOP_PARAMS)
    return ds, fit, float(corr[a, b]), condition(model, ds, LOOP_PARAMS)


def close_loop(out: Path, *, confounded_s: float, designed_s: float, domain: int) -> dict:
    """Step 4 up to the recordings: the slew-only recording (offline MuJoCo crane), ``cablelab
    excite`` on it for :data:`LOOP_PARAMS`, the designed reference played over DDS. Returns the
    paths and the design's condition numbers."""
    from ...description import load_description
    from ...excite import design, get_exciter, write_reference
    from .sim import CraneTruth, simulate, write_bag

    desc_text = (Path(__file__).parent / "data" / "crane.yaml").read_text()
    confounded, ref = out / "confounded", out / "designed_ref"
    log(f"crane: slew-only recording ({confounded_s:.0f} s, offline) with hidden offsets "
        f"{LOOP_OFFSET} and the payload mass free ...")
    truth = CraneTruth(torque_offset=LOOP_OFFSET, effort_noise=LOOP_NOISE, mocap_noise=0.0005)
    write_bag(confounded, simulate(truth, confounded_s, reference=slew_only(luff=REST_LUFF)), desc_text, overwrite=True)
    ds0, _, rho0, _ = loop_fit(confounded)
    log(f"crane: {', '.join(LOOP_PARAMS)} correlated {rho0:+.4f}: cablelab excite --params "
        f"'{','.join(LOOP_PARAMS)}' --duration {designed_s:g} ...")
    d = design("crane", load_description(desc_text), LOOP_PARAMS, duration=designed_s,
               before_ds=ds0, max_iter=10)
    write_reference(ref, d, get_exciter("crane"), desc_text, overwrite=True)
    log(f"crane: excite's condition number (nominal + offsets, all free) {d.condition_before:.4g} -> "
        f"{d.condition_after:.4g} ({d.seconds:.1f} s); pd_feedforward -p reference_bag:={ref} over DDS ...")
    designed = run_over_dds(out / "designed", out / "logs_designed", designed_s, domain,
                            sim={"offset": f"[{', '.join(repr(v) for v in LOOP_OFFSET)}]"},
                            controller={"reference_bag": str(ref)}, estimator=False)
    return {"confounded": confounded, "designed": designed, "reference": ref, "design_s": d.seconds}


def loop_rows(loop: dict) -> list:
    """Step 4's table rows: the pair's correlation and the parameters before and after."""
    _, f0, rho0, c0 = loop_fit(loop["confounded"])
    _, f1, rho1, c1 = loop_fit(loop["designed"])
    truth = described_params().payload_mass
    off = ", ".join(f"{v:g}" for v in LOOP_OFFSET)

    def params(f):
        p = f.params
        return (f"{p['OF[slew]']:+.3f} / {p['OF[luff]']:+.3f} / {p['OF[hoist]']:+.3f} ; "
                f"{p['m']:.3f}")

    return [
        ["loop: condition number of (OF[hoist], m) in the fitted model, slew-only -> designed",
         f"{c0:.4g} -> {c1:.4g}", "-"],
        ["loop: correlation OF[hoist] ~ m, slew-only -> designed", f"{rho0:+.4f} -> {rho1:+.4f}", "-"],
        ["loop: offsets slew / luff / hoist ; payload m (kg), slew-only", params(f0),
         f"sim {off} ; {truth:g}"],
        ["loop: same, designed reference over DDS", params(f1), f"sim {off} ; {truth:g}"],
    ]


def analyse(out: Path, bag_dir: Path, *, folds: int = 5, loop: dict | None = None) -> PartResult:
    """Steps 2-3 on a recorded bag: swing angles vs truth, diagnose + report, the table rows."""
    from ...bags import open_bag
    from . import plant as C
    from ...report import build_report
    from ...workbench import build_model, diagnose, load

    t_start = time.monotonic()
    params = described_params()
    tilt = tilt_for_rest_torque(params.first_moment, params.gravity)
    log("crane: swing angles (live estimate and cablelab estimate) vs ground truth ...")
    bag = open_bag(bag_dir)
    sw = swing_errors(bag)
    off = C.estimate_bag(bag)
    log("crane: diagnose + report (cablelab report) ...")
    plant, desc, ds = load(bag_dir, None, {})
    l_c = desc.crane.counterbalance.distance
    model = build_model(plant, desc, fixed={"l_c": l_c})   # 002 knew l_c: fixes the null direction
    d = diagnose(ds, model, plant.candidates(desc), folds=folds, greedy_mode=True)
    rep = build_report(ds, d, out / "report",
                       title="Boom crane demo: described crane, base tilt hidden (002 sec. 6.5)")
    steps = d.greedy
    ranking = d.ranking
    tilt_step = next((s for s in steps if s.added == "base_tilt"), None)
    K, g = params.first_moment, params.gravity
    fitted = rest_torque(tilt_step.params, K, g) if tilt_step else float("nan")
    true_rest = rest_torque({"tilt_x": np.sin(tilt), "tilt_y": 0.0}, K, g)
    final, nominal, nan = steps[-1].params, steps[0].params, float("nan")
    deg = np.degrees
    rows = [
        ["samples (100 Hz, lock-step over DDS)", f"{ds.n}", "-"],
        ["live swing RMS error theta1 / theta2 (deg)",
         f"{deg(sw['rms']['theta1']):.3f} / {deg(sw['rms']['theta2']):.3f}",
         "exact inverse of the measured pivots, not eq. 6.6-6.7"],
        ["max |theta1| / |theta2| swing (deg)",
         f"{deg(sw['range']['theta1']):.1f} / {deg(sw['range']['theta2']):.1f}", "-"],
        ["offline estimate RMS error theta1 / theta2 (deg)",
         f"{deg(off['rms_error_vs_ground_truth']['theta1']):.3f} / "
         f"{deg(off['rms_error_vs_ground_truth']['theta2']):.3f}", "-"],
        ["motion-capture dropouts handled", f"{off['conditioning'].get('dropouts', 0)}", "-"],
        ["diagnose: first effect", ranking[0].effect, "base_tilt (sec. 6.5)"],
        ["held-out NRMSE nominal -> + first effect",
         f"{100 * steps[0].error:.1f} % -> {100 * ranking[0].error_after:.1f} %", "-"],
        ["slew torque at rest, fitted tilt (N m)", f"{fitted:+.3f} (sim {true_rest:+.3f})",
         f"{PAPER_REST_TORQUE:+.1f}"],
        ["effects added by diagnose (waterfall)", " + ".join(s.added for s in steps[1:]) or "none",
         "base_tilt"],
        ["payload m / boom m_b / counterbalance m_c (kg)",
         f"{final.get('m', nan):.3f} / {final.get('m_b', nan):.3f} / "
         f"{final.get('m_c', nan):.3f}",
         f"sim {params.payload_mass} / {params.boom_mass} / {params.counterbalance_mass}"],
        ["I_tot / I_b (kg m^2): nominal -> final",
         f"{nominal.get('I_tot', nan):.3f} / {nominal.get('I_b', nan):.3f} -> "
         f"{final.get('I_tot', nan):.3f} / {final.get('I_b', nan):.3f}",
         "sim 0.05 / 0.02; 002 sec. 6.2: negative"],
    ]
    if loop is not None:
        rows += loop_rows(loop)
    page = crane_page(out / "report", bag_dir, rows, sw)
    bags = [bag_dir] + ([loop["confounded"], loop["designed"]] if loop is not None else [])
    return PartResult(bags=bags, rows=rows, report=rep.index, page=page,
                      first=ranking[0].effect, seconds=time.monotonic() - t_start)


def run(out: Path, *, duration: float = 30.0, folds: int = 5, domain: int = 1,
        loop_s: tuple[float, float] | None = (30.0, 60.0)) -> PartResult:
    """The whole crane part; ``out`` is its directory (``bags/demo/crane``). ``loop_s``: the
    durations of step 4's slew-only and designed recordings (None: no step 4)."""
    t0 = time.monotonic()
    bag = record(out, duration=duration, domain=domain)
    loop = close_loop(out, confounded_s=loop_s[0], designed_s=loop_s[1], domain=domain) if loop_s else None
    res = analyse(out, bag, folds=folds, loop=loop)
    res.seconds = time.monotonic() - t0
    return res


def add_arguments(group) -> None:
    group.add_argument("--crane-duration", type=float, default=30.0, help="crane: simulated s")
    group.add_argument("--crane-loop", type=float, nargs=2, default=(30.0, 60.0), metavar=("S1", "S2"),
                       help="crane: simulated s of the slew-only and the designed recording of the "
                            "confounded pair (OF[hoist], m); 0 0 skips that step")


def quick(a) -> None:
    """--quick: a 12 s run; the confounded pair on 10 s slew-only and a 10 s designed reference."""
    a.crane_duration = min(a.crane_duration, 12.0)
    a.crane_loop = tuple(min(x, 10.0) for x in a.crane_loop)


def _record(out: Path, a):
    from ...ros.launch import unique_domain_id

    bag = record(out, duration=a.crane_duration, domain=unique_domain_id(3))
    s1, s2 = a.crane_loop
    loop = close_loop(out, confounded_s=s1, designed_s=s2, domain=unique_domain_id(3)) if s1 > 0 and s2 > 0 else None
    return bag, loop


DEMO = DemoPart(plant="crane", title="Boom crane (002), hidden tilted base", order=20,
                add_arguments=add_arguments, record=_record,
                analyse=lambda out, a, runs: analyse(out, runs[0], folds=a.folds, loop=runs[1]),
                quick=quick, subdir="crane")
