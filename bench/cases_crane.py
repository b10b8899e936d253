"""Randomized boom-crane diagnosis cases (bench_diagnosis.py), generated WITHOUT the fitting code.

* truth: the MuJoCo crane of :mod:`cablelab.plants.crane.sim` (``build_mjcf``: slew, luff, gimbal
  swing joints and the hoist, built from the plant description; 002 ch. 3). The crane's fitting
  code never runs MuJoCo for the diagnosis: its regressor is the sympy-generated Lagrangian of 002
  eq. 4.1-4.2, so the two are separate implementations of the same mechanics. Added to it here:
  SMOOTH Coulomb friction ``-Fc tanh(qd / eps)`` on slew and luff (``qfrc_applied``, never the
  ``sign`` the fit uses), viscous joint damping, a tilted base (gravity rotated, 002 sec. 6.5), a
  torque-sensor offset, and the counterbalance either described or not (002 sec. 6.4).
* control: PD + MuJoCo's own bias forces (gravity, Coriolis) + diagonal inertia x reference
  acceleration at every 1 ms step (zero-order hold), tracking minimum-jerk point-to-point moves or
  chirp bursts of all three drives with the whole crane at rest 20-50 % of the time (the payload
  keeps swinging after a move, as on a real crane).
* sensors: efforts = motor commands + offset + AR(1) noise with outliers (unequal SNR per drive);
  encoder-quantized joint positions; joint velocity recorded or absent; motion-capture boom-tip
  and payload positions with 0.2-1 mm noise; 100 Hz or 200 Hz.

Hidden effects are drawn from the crane's candidates (``cablelab.plants.crane.plant.candidates``):
``joint_coulomb_friction``, ``torque_sensor_offset``, ``base_tilt``, ``counterbalance``,
``joint_viscous_friction``, ``time_delay`` (one, or two of them), plus control cases with nothing hidden. The
nominal model is the plant's (``crane_rigid_body`` + ``counterbalance`` when described) plus
``joint_viscous_friction`` (``--effects``) except in the viscous cases. The description's boom
mass and counterbalance are known parameters (``--fix m_b=.. --fix m_c=.. --fix l_c=..``): with
m_b free, (m_b, m_c, l_c) keep one unidentifiable direction (plants/crane/README.md), and a free
counterbalance moment absorbs a luff torque offset (cos(beta) over the luff range vs a constant).
When the counterbalance is the hidden effect only m_b is fixed, so its m_c and l_c are fitted.
The payload is a weighed calibration mass in every case (``--fix m=..``, the description's
``payload_mass``), as crane identification does it and as the diagnosis itself advises: with m free
the hoist force ``m (g cos.. - d_ddot) + OF[hoist]`` is nearly collinear with m (hoist accelerations
are a few % of g) and m carries into the luff gravity torque, so OF[luff], OF[hoist] came out up to
110 % wrong with the ranking flagging them "confounded with m" (correlation -0.99). The hoist
moves over 0.3-1.2 m of rope and its chirps reach 0.15 m (before: 0.4-0.9 m and 0.06 m, about
0.1 m/s in the chirps, where the hoist's viscous and Coulomb terms are below its force noise). ``base_tilt`` is scored on its two angles (tilt_x = -g_y / g,
tilt_y = g_x / g of gravity in the base frame).
``time_delay``: the recorded efforts are the motor commands of ``tau`` earlier (10-30 ms at
100/200 Hz): the 1 kHz command sequence is interpolated at ``t - tau`` here, the joint positions
and motion capture are not delayed (measured effort delayed relative to the motion).
"""
from __future__ import annotations

import mujoco
import numpy as np

from cases_common import PlantCase, coloured_noise, draw_slow_sines, moves_and_rests, quantize
from cablelab.plants.crane.reference import slew_only

JOINT_NAMES = ("slew", "luff", "hoist")
ONE = [("joint_coulomb_friction",), ("torque_sensor_offset",), ("base_tilt",), ("counterbalance",),
       ("joint_viscous_friction",), ("time_delay",)]
TWO = [("joint_coulomb_friction", "torque_sensor_offset"), ("joint_coulomb_friction", "base_tilt"),
       ("counterbalance", "joint_coulomb_friction"), ("base_tilt", "torque_sensor_offset"),
       ("joint_coulomb_friction", "time_delay")]
#: joint ranges of the reference moves: slew rad, luff rad, rope length m
LIMITS = ((-1.2, 1.2), (0.15, 1.1), (0.3, 1.2))
KP, KD = np.array([30.0, 40.0, 400.0]), np.array([10.0, 12.0, 40.0])


def draw_case(seed: int, kind: str | None = None) -> PlantCase:
    """A random crane case. ``kind``: "control", "one", "two" (default drawn 20/50/30 %)."""
    rng = np.random.default_rng(seed)
    if kind is None:
        kind = str(rng.choice(["control", "one", "two"], p=[0.2, 0.5, 0.3]))
    hidden = () if kind == "control" else (ONE[rng.integers(len(ONE))] if kind == "one"
                                           else TWO[rng.integers(len(TWO))])
    lb, m, mb = rng.uniform(0.8, 1.2), rng.uniform(0.3, 1.0), rng.uniform(0.5, 1.5)
    mc, lc = rng.uniform(1.0, 3.0), rng.uniform(0.2, 0.4)
    truth = {"boom_length": lb, "payload_mass": m, "boom_mass": mb, "counterbalance_mass": mc,
             "counterbalance_distance": lc, "slew_inertia": rng.uniform(0.03, 0.1),
             "luff_inertia": rng.uniform(0.01, 0.04),
             "viscous": [rng.uniform(0.05, 0.3), rng.uniform(0.05, 0.3), rng.uniform(0.5, 2.0)],
             "coulomb": [0.0, 0.0, 0.0], "offset": [0.0, 0.0, 0.0], "tilt": [0.0, 0.0],
             # smooth Coulomb band: 0.2-1 % of each drive's typical peak speed (rad/s, rad/s, m/s)
             "eps": list(rng.uniform(0.002, 0.01) * np.array([0.5, 0.2, 0.1]))}
    # typical efforts: slew ~ J alpha_dd, luff ~ boom-side moment x g, hoist ~ m g
    J = lb * lb * (m + mb / 4) + lc * lc * mc + truth["slew_inertia"]
    K = abs(lb * m + lb * mb / 2 - lc * mc)
    f_typ = np.array([0.3 * J + 0.3 * truth["viscous"][0], K * 9.81 * 0.5 + 0.5, m * 9.81])
    if "joint_coulomb_friction" in hidden:
        truth["coulomb"] = [rng.uniform(0.15, 0.4) * f_typ[0], rng.uniform(0.1, 0.3) * f_typ[1], 0.0]
    if "torque_sensor_offset" in hidden:
        truth["offset"] = list(rng.choice([-1, 1], 3) * rng.uniform(0.05, 0.2, 3) * f_typ)
    if "base_tilt" in hidden:
        truth["tilt"] = list(rng.choice([-1, 1], 2) * np.radians(rng.uniform(1.0, 3.0, 2)))
    effects = () if "joint_viscous_friction" in hidden else ("joint_viscous_friction",)
    fs = float(rng.choice([100.0, 200.0]))
    profile = str(rng.choice(["ptp", "chirp"]))
    # the description's boom mass and (when described) counterbalance are known parameters, and
    # the payload is a weighed calibration mass (m known): see the module docstring
    fixed = {"m_b": mb, "m": m} if "counterbalance" in hidden else {"m_b": mb, "m": m, "m_c": mc, "l_c": lc}
    case = PlantCase(plant="crane", seed=seed, family=profile, fs=fs, hidden=tuple(hidden),
                     description=_description(truth, with_cb="counterbalance" not in hidden),
                     effects=effects, fixed=fixed, truth=truth,
                     velocity_recorded=bool(rng.random() < 0.4))
    case.truth.update(duration=float(rng.uniform(40, 60)), profile=case.family,
                      rest_fraction=float(rng.uniform(0.2, 0.5)),
                      noise_rel=list(10 ** rng.uniform(-2, np.log10(0.05), 3)), ar=float(rng.uniform(0, 0.8)),
                      outlier_rate=float(rng.choice([0.0, 0.002])), mocap_noise=float(rng.uniform(2e-4, 1e-3)),
                      quantum=[2 * np.pi / 2 ** int(rng.integers(16, 19)), 2 * np.pi / 2 ** int(rng.integers(16, 19)),
                               10.0 ** rng.uniform(-6, -5)])
    tau = float(rng.uniform(10e-3, 30e-3))          # drawn last: the other draws do not depend on it
    case.truth["tau"] = tau if "time_delay" in hidden else 0.0
    case.true_params = _true_params(case)
    return case


# ----------------------------------------------------------------------------- designed experiments

#: the pair a slew-only recording confounds when the payload is not weighed: the payload's weight
#: ``m g`` and the hoist offset are both constants on the hoist (the slew axis is vertical, so no
#: weight reaches it); what ``cablelab excite`` is asked to separate
PAIR = ("OF[hoist]", "m")


def draw_designed_case(seed: int, kind: str | None = None) -> PlantCase:
    """A case whose first recording does not separate what is hidden: the crane only slews (luff
    and rope held) for ``first_s`` s, the payload is not weighed (m free) and, unless ``kind`` is
    "control" (default: every fourth seed), the effort offsets of all three drives are hidden. The benchmark
    then designs an excitation for :data:`PAIR` on that recording and simulates it with
    :func:`simulate` (``reference``)."""
    rng = np.random.default_rng(seed + 104729)
    if kind is None:
        kind = "control" if seed % 4 == 3 else "pair"
    case = draw_case(seed, kind="control")
    tr = case.truth
    if kind == "pair":
        J = tr["boom_length"] ** 2 * (tr["payload_mass"] + tr["boom_mass"] / 4) \
            + tr["counterbalance_distance"] ** 2 * tr["counterbalance_mass"] + tr["slew_inertia"]
        K = abs(tr["boom_length"] * (tr["payload_mass"] + tr["boom_mass"] / 2)
                - tr["counterbalance_distance"] * tr["counterbalance_mass"])
        f_typ = np.array([0.3 * J + 0.3 * tr["viscous"][0], K * 9.81 * 0.5 + 0.5, tr["payload_mass"] * 9.81])
        tr["offset"] = list(rng.choice([-1, 1], 3) * rng.uniform(0.05, 0.2, 3) * f_typ)
        case.hidden = ("torque_sensor_offset",)
        case.true_params = {"torque_sensor_offset": {f"OF[{j}]": v for j, v in zip(JOINT_NAMES, tr["offset"])},
                            "payload mass": {"m": tr["payload_mass"]}}
    else:
        case.true_params = {"payload mass": {"m": tr["payload_mass"]}}
    case.fixed = {k: v for k, v in case.fixed.items() if k != "m"}      # the payload is not weighed
    case.family = f"designed {kind}"
    # the designed runs swing the payload near the 3 Hz cut-off: the parallel filter keeps the
    # equations exact there (positions alone left 2-3 % of the hoist and luff offsets); on plain
    # recordings it is not the default because of the fit's noise weights (filter_noise_study)
    case.options = {**case.options, "crane_filter": "parallel"}
    amp, f = rng.uniform(0.3, 0.6), rng.uniform(0.08, 0.15)
    tr.update(first_s=30.0, designed_s=60.0, slew_amp=amp, slew_hz=f, reference=slew_only(amp, f))
    return case


#: the pair a slow recording leaves a hidden delay confounded in: the effort of a motion much slower
#: than tau barely changes within tau, so the delay's column (minus the output's time derivative,
#: linearised) is small and close to the inertia's (the acceleration's) columns
DELAY_PAIR = ("tau", "I_tot")


def draw_delay_case(seed: int, kind: str | None = None) -> PlantCase:
    """A case whose first recording hides a measurement delay (20-45 ms, "delay") or nothing
    ("control", every fourth seed): ``first_s`` s of slow sines of all three drives (0.02-0.05 Hz,
    where tau shifts the effort by less than its noise), masses weighed as in :func:`draw_case`.
    The benchmark diagnoses that recording, designs an excitation for :data:`DELAY_PAIR`
    (``truth["pair"]``) on it and simulates it with :func:`simulate`."""
    rng = np.random.default_rng(seed + 15485863)
    if kind is None:
        kind = "control" if seed % 4 == 3 else "delay"
    case = draw_case(seed, kind="control")
    tr = case.truth
    if kind == "delay":
        tr["tau"] = float(rng.uniform(20e-3, 45e-3))
        case.hidden = ("time_delay",)
        case.true_params = {"time_delay": {"tau": tr["tau"]}}
    else:
        tr["tau"] = 0.0
        case.true_params = {}
    case.family = f"designed {kind}"
    tr.update(first_s=60.0, designed_s=60.0, pair=DELAY_PAIR, diagnose_first=True,
              reference=draw_slow_sines(rng, LIMITS))
    return case


def tabulated(t_ref, q, qd, qdd):
    """Reference ``fn(t)`` interpolating a designed motion (held at its last point after the end)."""
    def fn(t):
        t = np.asarray(t, float)
        return tuple(np.column_stack([np.interp(t, t_ref, a[:, j]) for j in range(a.shape[1])])
                     for a in (q, qd, qdd))

    return fn


def _description(tr: dict, with_cb: bool) -> str:
    y = (f"plant: crane\ngravity: 9.81\ncrane:\n  boom_length: {tr['boom_length']:.6g}\n"
         f"  payload_mass: {tr['payload_mass']:.6g}\n  boom_mass: {tr['boom_mass']:.6g}\n")
    if with_cb:
        y += (f"  counterbalance: {{mass: {tr['counterbalance_mass']:.6g}, "
              f"distance: {tr['counterbalance_distance']:.6g}}}\n")
    return y


def _gravity_in_base(tilt, g=9.81) -> np.ndarray:
    """Gravity in the tilted base frame: base rotated by tilt[0] about world x, then tilt[1]
    about y; g_base = (Ry Rx)^T [0, 0, -g]."""
    cx, sx, cy, sy = np.cos(tilt[0]), np.sin(tilt[0]), np.cos(tilt[1]), np.sin(tilt[1])
    rx = np.array([[1, 0, 0], [0, cx, -sx], [0, sx, cx]])
    ry = np.array([[cy, 0, sy], [0, 1, 0], [-sy, 0, cy]])
    return (ry @ rx).T @ np.array([0.0, 0.0, -g])


def _true_params(case: PlantCase) -> dict:
    tr = case.truth
    out = {}
    if "joint_coulomb_friction" in case.hidden:
        out["joint_coulomb_friction"] = {f"Fc[{j}]": v for j, v in zip(JOINT_NAMES, tr["coulomb"])}
    if "torque_sensor_offset" in case.hidden:
        out["torque_sensor_offset"] = {f"OF[{j}]": v for j, v in zip(JOINT_NAMES, tr["offset"])}
    if "joint_viscous_friction" in case.hidden:
        out["joint_viscous_friction"] = {f"Fv[{j}]": v for j, v in zip(JOINT_NAMES, tr["viscous"])}
    if "counterbalance" in case.hidden:
        out["counterbalance"] = {"m_c": tr["counterbalance_mass"], "l_c": tr["counterbalance_distance"]}
    if "base_tilt" in case.hidden:
        # the base_tilt angles (002 sec. 6.5) are defined by the horizontal gravity in the base
        # frame: tilt_x = -g_y / g, tilt_y = g_x / g (exactly; to first order the base rotations
        # about world x and y that the simulator applies)
        gb = _gravity_in_base(tr["tilt"])
        out["base_tilt"] = {"tilt_x": -gb[1] / 9.81, "tilt_y": gb[0] / 9.81}
    if "time_delay" in case.hidden:
        out["time_delay"] = {"tau": tr["tau"]}
    return out


# ----------------------------------------------------------------------------- reference motion

def reference(case: PlantCase, rng):
    """Joint reference of the three drives, ``fn(t) -> (q, qd, qdd)`` (N, 3) each: moves of all
    drives together (minimum-jerk point to point, or chirp bursts below the payload's pendulum
    frequency) separated by rests (:func:`cases_common.moves_and_rests`)."""
    tr = case.truth
    if tr.get("reference") is not None:       # a given reference (designed-experiment cases)
        tr["end"] = tr["duration"]
        return tr["reference"]
    r, end = moves_and_rests(rng, [0.0, 0.5, 0.6], LIMITS, tr["duration"], tr["rest_fraction"], tr["profile"],
                             move_time=3.5 if tr["profile"] == "ptp" else 5.0, chirp_amp=[0.4, 0.12, 0.15])
    case.truth["end"] = end
    return r


# ----------------------------------------------------------------------------- truth simulation

def simulate(case: PlantCase) -> dict:
    """Closed-loop MuJoCo run of the crane (1 ms steps) sampled at ``case.fs``; returns the recorded
    signals: ``t``, ``q`` (N, 3) encoder readings, ``qd`` (N, 3) or NaN, ``effort`` (N, 3), ``tip``,
    ``payload`` (N, 3) motion capture and their quaternions x, y, z, w, plus the true motor efforts."""
    from cablelab.plants.crane.model import CraneParams
    from cablelab.plants.crane.mjcf import build_mjcf
    from cablelab.plants.crane.sim import CraneTruth, set_state

    rng = np.random.default_rng(case.seed + 7919)
    tr = case.truth
    ref = reference(case, rng)
    params = CraneParams(**{k: tr[k] for k in ("boom_length", "payload_mass", "boom_mass", "counterbalance_mass",
                                               "counterbalance_distance", "slew_inertia", "luff_inertia")})
    model = build_mjcf(CraneTruth(params=params, base_tilt=tuple(tr["tilt"]), viscous=tuple(tr["viscous"]),
                                   effort_limit=(1e3, 1e3, 1e3)))
    data = mujoco.MjData(model)
    dt = model.opt.timestep
    dec = int(round(1.0 / (case.fs * dt)))
    n = int(round(tr["duration"] / dt))
    tgrid = np.arange(n) * dt
    qr, vr, ar = ref(tgrid)
    set_state(model, data, [qr[0, 0], qr[0, 1], qr[0, 2], 0.0, 0.0])
    idx = np.array([0, 1, 4])                       # slew, luff, hoist dofs
    fc, eps = np.asarray(tr["coulomb"], float), np.asarray(tr["eps"], float)
    m = (n + dec - 1) // dec
    qpos, qvel, sens, ctrl = np.empty((m, 5)), np.empty((m, 5)), np.empty((m, model.nsensordata)), np.empty((m, 3))
    u_all = np.empty((n, 3))                        # every 1 kHz command, for a delayed measurement
    madr = (model.M_rowadr + model.M_rownnz - 1)[idx]   # diagonal of the sparse mass matrix (data.M)
    j = 0
    for k in range(n):  # the 1 kHz control loop (feedback every step, zero-order hold)
        v = data.qvel[idx]
        mujoco.mj_fwdPosition(model, data)          # mass matrix and bias of this state
        mujoco.mj_fwdVelocity(model, data)
        u = KP * (qr[k] - data.qpos[idx]) + KD * (vr[k] - v) + data.qfrc_bias[idx] + data.M[madr] * ar[k]
        data.ctrl[:] = u
        u_all[k] = u
        data.qfrc_applied[idx] = -fc * np.tanh(v / eps)   # smooth Coulomb friction (truth)
        if k % dec == 0:
            qpos[j], qvel[j], ctrl[j] = data.qpos, data.qvel, u
        mujoco.mj_step(model, data)
        if k % dec == 0:
            sens[j] = data.sensordata                # computed at the state before the step
            j += 1
    t = tgrid[::dec]
    # the effort measured at t is the command of t - tau (tau = 0: the sampled command itself)
    motor = (ctrl if tr.get("tau", 0.0) == 0.0 else
             np.column_stack([np.interp(t - tr["tau"], tgrid, u_all[:, i]) for i in range(3)]))
    eff = np.empty_like(motor)
    for i in range(3):
        sigma = tr["noise_rel"][i] * float(np.sqrt(np.mean(motor[:, i] ** 2)))
        eff[:, i] = motor[:, i] + tr["offset"][i] + coloured_noise(rng, m, sigma, tr["ar"], tr["outlier_rate"])
    q = np.column_stack([quantize(qpos[:, [0, 1, 4][i]], tr["quantum"][i]) for i in range(3)])
    qd = (qvel[:, idx] + rng.standard_normal((m, 3)) * [0.002, 0.002, 0.001] if case.velocity_recorded
          else np.full((m, 3), np.nan))
    tip = sens[:, 13:16] + rng.normal(scale=tr["mocap_noise"], size=(m, 3))
    pay = sens[:, 20:23] + rng.normal(scale=tr["mocap_noise"], size=(m, 3))
    return {"t": t, "q": q, "qd": qd, "effort": eff, "motor": motor, "tip": tip, "payload": pay,
            "tip_quat": sens[:, [17, 18, 19, 16]], "payload_quat": sens[:, [24, 25, 26, 23]],
            "q_true": qpos, "qd_true": qvel}


def write_bag(case: PlantCase, path, rec: dict | None = None) -> dict:
    """Simulate (unless ``rec`` is given) and write the case as a crane bag: ``/crane/joint_states``
    (slew, luff, hoist), ``/crane/boom_tip_pose``, ``/crane/payload_pose``, ``/plant_description``."""
    from cablelab.bags import BagWriter

    rec = rec if rec is not None else simulate(case)
    t = rec["t"] + 1.0
    with BagWriter(path, overwrite=True) as w:
        w.write_description(case.description)
        w.write_joint_states("/crane/joint_states", t, JOINT_NAMES, position=rec["q"], velocity=rec["qd"],
                             effort=rec["effort"])
        w.write_poses("/crane/boom_tip_pose", t, rec["tip"], rec["tip_quat"])
        w.write_poses("/crane/payload_pose", t, rec["payload"], rec["payload_quat"])
    return rec


# ----------------------------------------------------------------------------- the dataset filter's noise study

#: the sensor noise of a case, removed for its noise-free twin (quantum: a position step far below
#: any motion; the coloured noise of zero sigma adds nothing)
NOISE_FREE = {"noise_rel": [0.0, 0.0, 0.0], "outlier_rate": 0.0, "mocap_noise": 0.0, "quantum": [1e-12] * 3}


def add_noise(case: PlantCase, clean: dict, rng) -> dict:
    """The sensors of :func:`simulate` applied to a noise-free run ``clean`` of the same case (its
    ``motor``, ``q_true``, noise-free motion capture) with a new noise realisation ``rng``: AR(1)
    effort noise with outliers, encoder quantization, motion-capture noise. The motion is the
    same for every realisation, so the spread over realisations is the estimate's noise alone."""
    tr = case.truth
    rec = dict(clean)
    m = rec["t"].size
    eff = rec["motor"].copy()
    for i in range(3):
        sigma = tr["noise_rel"][i] * float(np.sqrt(np.mean(rec["motor"][:, i] ** 2)))
        eff[:, i] += coloured_noise(rng, m, sigma, tr["ar"], tr["outlier_rate"])
    rec["effort"] = eff
    rec["q"] = np.column_stack([quantize(rec["q_true"][:, [0, 1, 4][i]], tr["quantum"][i]) for i in range(3)])
    rec["tip"] = clean["tip"] + rng.normal(scale=tr["mocap_noise"], size=(m, 3))
    rec["payload"] = clean["payload"] + rng.normal(scale=tr["mocap_noise"], size=(m, 3))
    return rec


#: the band (Hz) of the study's experimental channel weights: below the swing and the 3 Hz cut-off,
#: the band of the moves (chirps and point-to-point moves below the pendulum frequency)
STUDY_BAND_HZ = 1.0


def fit_true_model(case: PlantCase, path, crane_filter: str, channel_scale=None):
    """The case's bag fitted with its true model (nominal + hidden effects, the case's known
    parameters) under the dataset filter ``crane_filter``; ``channel_scale`` as
    :func:`cablelab.fit.identify` (None: its noise weights; "rms"), or "band": an experiment, not
    the fit's weighting: the noise weights of the RMS-weighted fit's residual low-passed at
    :data:`STUDY_BAND_HZ` (the noise where the moves' information is, whatever the filter)."""
    from cablelab import workbench
    from cablelab.fit import identify
    from cablelab.fit.identification import noise_weights
    from cablelab.parallel_filter import parallel_filter

    plant, desc, ds = workbench.load(path, None, {**case.options, "crane_filter": crane_filter})
    model = workbench.build_model(plant, desc, tuple(case.effects) + tuple(case.hidden), fixed=case.fixed)
    if isinstance(channel_scale, str) and channel_scale == "band":
        first = identify(model, ds, channel_scale="rms")
        ok = ds.valid & np.isfinite(first.residual).all(axis=1)
        low = parallel_filter(np.where(ok[:, None], first.residual, 0.0), ds.t, STUDY_BAND_HZ)
        channel_scale = noise_weights(low[ok])
    return identify(model, ds, channel_scale=channel_scale)


def filter_noise_study(seed: int, draws: int, workdir: str) -> list[dict]:
    """The counterbalance of case ``seed`` (hidden) under both dataset filters and both channel
    weightings: on its noise-free twin, on the benchmark's own recording, and over ``draws``
    noise realisations of the same motion (mean, spread, and the spread of the difference between
    the filters on the same realisation). Relative errors of m_c in %."""
    import copy
    import os

    case = draw_case(seed)
    assert "counterbalance" in case.hidden, case.hidden
    m_c = case.true_params["counterbalance"]["m_c"]
    twin = copy.deepcopy(case)
    twin.truth.update(NOISE_FREE)
    clean = simulate(twin)
    bags = {"noise-free": (os.path.join(workdir, f"crane_{seed}_clean"), clean),
            "recording": (os.path.join(workdir, f"crane_{seed}"), None)}
    for k in range(draws):
        bags[k] = (os.path.join(workdir, f"crane_{seed}_{k}"), add_noise(case, clean, np.random.default_rng(1000 + k)))
    for name, (path, rec) in bags.items():
        write_bag(twin if name == "noise-free" else case, path, rec)
    rows = []
    for weights in (None, "rms", "band"):
        errs = {}
        for flt in ("positions", "parallel"):
            e = {}
            for name, (path, _) in bags.items():
                r = fit_true_model(case, path, flt, weights)
                e[name] = ((r.params["m_c"] - m_c) / m_c * 100, r.stderr["m_c"] / m_c * 100,
                           np.asarray(r.linear.channel_scale, float))
            errs[flt] = e
        for flt, e in errs.items():
            mc = np.array([e[k][0] for k in range(draws)])
            other = errs["parallel" if flt == "positions" else "positions"]
            diff = mc - np.array([other[k][0] for k in range(draws)])
            rows.append({"seed": seed, "hidden": "+".join(case.hidden), "filter": flt,
                         "weights": {None: "noise (default)", "band": f"band {STUDY_BAND_HZ:g} Hz"}.get(weights, weights),
                         "noise_free": e["noise-free"][0], "recording": e["recording"][0],
                         "recording_se": e["recording"][1], "mean": float(mc.mean()), "sd": float(mc.std(ddof=1)),
                         "pair_sd": float(diff.std(ddof=1)), "quoted_se": float(np.median([e[k][1] for k in range(draws)])),
                         "w": e["recording"][2] / e["recording"][2][1]})
    return rows


def delay_filter_study(seed: int, workdir: str) -> dict:
    """The delay case ``seed`` (:func:`draw_delay_case`, a delay hidden): its first recording,
    ``excite``'s design for :data:`DELAY_PAIR` on it, the designed run, as bench_diagnosis makes
    them; the designed run fitted with the true model (time_delay added) under both filters, each
    with its own noise weights and with the other filter's. Relative errors of tau in %."""
    import os

    from cablelab import workbench
    from cablelab.excite import design

    case = draw_delay_case(seed)
    tr = case.truth
    tau = tr["tau"]
    assert tau > 0, "a control case"
    first, path = os.path.join(workdir, f"delay_{seed}_first"), os.path.join(workdir, f"delay_{seed}")
    tr["duration"] = tr["first_s"]
    write_bag(case, first)
    plant, desc, ds0 = workbench.load(first, None, dict(case.options))
    d = design(case.plant, desc, tuple(tr["pair"]), duration=tr["designed_s"], before_ds=ds0, seed=case.seed,
               effects=case.effects, fixed=case.fixed)
    tr["duration"], tr["reference"] = tr["designed_s"], tabulated(d.t, d.q, d.qd, d.qdd)
    write_bag(case, path)
    own = {f: fit_true_model(case, path, f) for f in ("positions", "parallel")}
    out = {"seed": seed, "tau_ms": tau * 1e3}
    for f, other in (("positions", "parallel"), ("parallel", "positions")):
        swapped = fit_true_model(case, path, f, own[other].linear.channel_scale)
        out[f] = ((own[f].params["tau"] - tau) / tau * 100, own[f].stderr["tau"] / tau * 100,
                  (swapped.params["tau"] - tau) / tau * 100)
    return out


def _print_delay(seeds):
    import tempfile

    print("time_delay tau, signed rel. error % on the designed run (the quoted standard error in brackets): "
          "true model fitted, each filter with its own noise weights and with the other filter's")
    hdr = "seed  tau ms  positions (se)   parallel (se)   positions, parallel's weights  parallel, positions' weights"
    print(hdr)
    print("-" * len(hdr))
    with tempfile.TemporaryDirectory() as wd:
        for s in seeds:
            r = delay_filter_study(s, wd)
            print(f"{s:<5d} {r['tau_ms']:6.1f}  {r['positions'][0]:+8.2f} ({r['positions'][1]:3.1f})  "
                  f"{r['parallel'][0]:+8.2f} ({r['parallel'][1]:3.1f})  {r['positions'][2]:+29.2f}  "
                  f"{r['parallel'][2]:+28.2f}", flush=True)


def _print_filter_noise(seeds, draws):
    import tempfile

    print(f"counterbalance m_c, signed rel. error % (the quoted standard error in brackets): true model fitted, {draws} noise realisations of each case's motion")
    hdr = ("seed  hidden                            filter     weights          noise-free  recording (se)"
           "    draws mean   sd  |diff| sd  quoted se  weights slew:luff:hoist")
    print(hdr)
    print("-" * len(hdr))
    with tempfile.TemporaryDirectory() as wd:
        for s in seeds:
            for r in filter_noise_study(s, draws, wd):
                print(f"{r['seed']:<5d} {r['hidden']:<33s} {r['filter']:<10s} {r['weights']:<16s} "
                      f"{r['noise_free']:+10.2f}  {r['recording']:+8.2f} ({r['recording_se']:4.1f})"
                      f"  {r['mean']:+10.2f} {r['sd']:5.2f}  {r['pair_sd']:9.2f}  {r['quoted_se']:9.1f}  "
                      + ":".join(f"{x:.2f}" for x in r["w"]), flush=True)


if __name__ == "__main__":      # ./run python bench/cases_crane.py --filter-noise 2005,2013,2021 | --delay 8000,8001
    import argparse

    ap = argparse.ArgumentParser(description="The crane dataset filter's counterbalance estimate against "
                                             "noise: noise-free twin, the benchmark's recording, noise realisations.")
    ap.add_argument("--filter-noise", default="2005,2013,2021", help="seeds of counterbalance cases")
    ap.add_argument("--draws", type=int, default=12)
    ap.add_argument("--delay", default="", help="seeds of delay cases (draw_delay_case) instead")
    a = ap.parse_args()
    if a.delay:
        _print_delay([int(s) for s in a.delay.split(",")])
    else:
        _print_filter_noise([int(s) for s in a.filter_noise.split(",")], a.draws)
