"""The boom-crane plant (002; CONTRACT sections 2-3, prefix ``/crane``): workbench plug-in and
the offline swing estimate behind ``cablelab estimate``.

Pieces, one module each:

* :mod:`.crane_kinematics` - boom tip, payload, exact swing angles (CONTRACT sec. 2, 002 sec. 6.3);
* :mod:`.crane_symbolic` -> :mod:`.crane_dynamics_generated` - regressor Y(q, qd, qdd) from the
  energies of 002 eq. A.3-A.4 (sympy, generated once);
* :mod:`.crane_model` - :class:`CraneParams`, pi of 002 eq. 4.2, M, G, inverse dynamics;
* :mod:`.crane_identify` - stacked regressor, rank 6, base parameters, 002's fixing, bounds;
* :mod:`.crane_swing` - swing estimation offline (vectorised) and live (:class:`SwingTracker`);
* :mod:`.crane_control` - PD + gravity compensation + reference-acceleration feedforward;
* :mod:`.crane_freerun` - free-run comparison of an identified model (002 sec. 6.1, 6.4);
* :mod:`cablelab.plants.crane.effects` - ``crane_rigid_body``, ``counterbalance``, ``base_tilt``;
* :mod:`cablelab.plants.crane.sim` - the MuJoCo crane with its truth switches.

Workbench dataset: channels slew torque (N m), luff torque (N m), hoist force (N) from
``/crane/joint_states``; q = [alpha, beta, d, theta1, theta2] with alpha, beta, d from the joint
states and theta1, theta2 from the motion-capture poses (interpolated at the joint-state stamps),
conditioned by :func:`cablelab.conditioning.condition_motion` (unwrap, uniform grid, zero-phase
Butterworth, central differences), and the signal ``Y`` = the 5 x 9 regressor per sample.
"""
from __future__ import annotations

import dataclasses

import numpy as np

from ...conditioning import Conditioning, condition_motion
from ...errors import CablelabError
from ...dataset import STANDARD_GRAVITY, Dataset
from ...registry import Plant, register_plant
from .description import parse_section
from .dynamics_generated import regressor
from .freerun import fit_free_run, free_run_compare
from .kinematics import SwingAngles
from .model import JOINTS, CraneParams
from .swing import SwingReport, estimate_swing

JOINT_STATES = "/crane/joint_states"
TIP_POSE = "/crane/boom_tip_pose"
PAYLOAD_POSE = "/crane/payload_pose"
SWING_ESTIMATE = "/crane/swing_estimate"
SWING_TRUTH = "/crane/ground_truth/swing"
REFERENCE = "/crane/reference"
EFFORT_COMMANDS = "/crane/effort_commands"
JOINT_STATE = "sensor_msgs/msg/JointState"
POSE = "geometry_msgs/msg/PoseStamped"
SWING_NAMES = ("theta1", "theta2", "rope_length")
#: default low-pass cut-off of the crane's positions, Hz (when --cutoff is not given). The payload
#: swings at sqrt(g / d) / (2 pi) ~ 0.6-1 Hz and the excitation stays below ~0.5 Hz, while
#: motion-capture noise is differentiated twice for the swing accelerations: the generic fs / 10
#: (10 Hz at 100 Hz) lets 1 mm of noise become metres per second squared (002 sec. 5.1.3 chose
#: its filters case by case; this is the case for the crane).
CRANE_CUTOFF_HZ = 3.0

__all__ = ["CraneParams", "dataset", "dataset_from_arrays", "estimate_bag", "swing_from_bag",
           "write_swing_estimate", "baseline", "candidates", "CRANE"]


def _swing_regimes(theta1: np.ndarray, theta2: np.ndarray) -> np.ndarray:
    amp = np.hypot(theta1, theta2)
    edges = np.quantile(amp, [1 / 3, 2 / 3])
    labels = np.array([f"swing < {edges[0]:.2g} rad", f"swing {edges[0]:.2g}-{edges[1]:.2g} rad",
                       f"swing > {edges[1]:.2g} rad"])
    return labels[np.searchsorted(edges, amp)]


def dataset_from_arrays(t, q_joints, effort, t_mocap, tip, payload, description,
                        options: dict | None = None, *, source: str = "data") -> Dataset:
    """Crane dataset from raw arrays.

    Args:
        t: (N,) joint-state stamps, s. q_joints: (N, 3) [alpha rad, beta rad, d m].
        effort: (N, 3) [slew N m, luff N m, hoist N].
        t_mocap, tip, payload: (M,), (M, 3), (M, 3) motion capture (NaN rows = dropouts).
        description: :class:`~cablelab.description.Description` with a ``crane`` section.
        options: ``{"conditioning": Conditioning}``.
    """
    options = options or {}
    opts = options.get("conditioning") or Conditioning()
    if opts.cutoff_hz is None:
        opts = dataclasses.replace(opts, cutoff_hz=CRANE_CUTOFF_HZ)
    t = np.asarray(t, dtype=float)
    q_joints = np.asarray(q_joints, dtype=float).reshape(-1, 3)
    ok = np.isfinite(t) & np.isfinite(q_joints[:, 0])
    sw, rep = estimate_swing(t_mocap, tip, payload, t[ok], q_joints[ok, 0], source=source)
    th1 = np.interp(t, sw.t, sw.theta1)
    th2 = np.interp(t, sw.t, sw.theta2)
    q5 = np.column_stack([q_joints, th1, th2])
    c = condition_motion(t, q5, np.asarray(effort, float), opts,
                         revolute=[True, True, False, True, True], source=source)
    g = description.gravity if description is not None else STANDARD_GRAVITY
    q, qd, qdd = c["q"], c["qd"], c["qdd"]
    Y = regressor(q, qd, qdd, g)
    ds = Dataset(
        plant="crane", t=c["t"], y=c["effort"], channels=JOINTS, units=("N m", "N m", "N"),
        signals={"q": q, "qd": qd, "qdd": qdd, "Y": Y,
                 "boom_length": description.crane.boom_length if description is not None else 1.0},
        actuators=JOINTS, act_vel=qd[:, :3],
        act_units=(("N m", "rad"), ("N m", "rad"), ("N", "m")),
        inputs={"slew velocity": qd[:, 0], "luff velocity": qd[:, 1], "slew angle": q[:, 0],
                "theta1": q[:, 3], "theta2": q[:, 4]},
        regimes={"payload swing": _swing_regimes(q[:, 3], q[:, 4])},
        description=description, source=source,
    )
    # drives that stop (issue 10): samples in the zero-speed zone of slew, luff or hoist are not
    # fitted, as for the axis (cablelab.velocity): there the smooth friction band holds any
    # effort and the sign of a filtered, quantized encoder velocity is noise
    from ...velocity import exclude_zero_speed, position_quantum, speed_resolution

    ok_q = q_joints[ok]
    floor = np.array([speed_resolution(position_quantum(ok_q[:, j]), c["cutoff_hz"]) for j in range(3)])
    return exclude_zero_speed(ds, floor=floor)


def swing_from_bag(bag, *, cutoff_hz: float | None = None) -> tuple[SwingAngles, SwingReport]:
    """Swing estimate over a bag: motion-capture poses + slew angle of ``/crane/joint_states``."""
    for topic, typ in ((JOINT_STATES, JOINT_STATE), (TIP_POSE, POSE), (PAYLOAD_POSE, POSE)):
        bag.require(topic, typ)
    js = bag.joint_state(JOINT_STATES, ["slew"])
    tip = bag.pose(TIP_POSE)
    pay = bag.pose(PAYLOAD_POSE)
    if tip.t.shape != pay.t.shape or not np.array_equal(tip.t, pay.t, equal_nan=True):
        # different stamps: bring the payload onto the tip stamps (NaN outside its range)
        ok = np.isfinite(pay.t) & np.isfinite(pay.position).all(1)
        if ok.sum() < 2:
            raise CablelabError(f"{bag.path}: {PAYLOAD_POSE} has fewer than 2 finite poses")
        order = np.argsort(pay.t[ok])
        tp = pay.t[ok][order]
        pos = np.column_stack([np.interp(tip.t, tp, pay.position[ok][order][:, i], left=np.nan,
                                         right=np.nan) for i in range(3)])
    else:
        pos = pay.position
    return estimate_swing(tip.t, tip.position, pos, js.t, js.position[:, 0], cutoff_hz=cutoff_hz,
                          source=str(bag.path))


def _stats(x: np.ndarray) -> dict:
    x = x[np.isfinite(x)]
    return {"mean": float(np.mean(x)), "std": float(np.std(x)), "max_abs": float(np.max(np.abs(x)))}


def estimate_bag(bag, description=None, *, out=None, cutoff_hz: float | None = None,
                 overwrite: bool = False, **_options) -> dict:
    """``cablelab estimate`` for a crane bag: swing-angle statistics (CONTRACT sec. 5) as JSON.

    Args:
        bag: bag path or an open :class:`~cablelab.bags.Bag`.
        description: unused (the swing estimate needs no parameters); kept for the verb's API.
        out: also write the per-sample estimates as ``/crane/swing_estimate`` (stamped like the
            motion capture) to this bag.
        cutoff_hz: optional low-pass of the angles before differentiation.
    Other options of the verb (``tensions``, ``effects``, ``pose``) do not apply to the crane.
    """
    if not hasattr(bag, "pose"):
        from ...bags import open_bag

        bag = open_bag(bag)
    sw, rep = swing_from_bag(bag, cutoff_hz=cutoff_hz)
    res = {"plant": "crane", "samples": int(sw.t.shape[0]),
           "theta1": _stats(sw.theta1), "theta2": _stats(sw.theta2),
           "rope_length": _stats(sw.rope_length),
           "theta1_dot": _stats(sw.theta1_dot), "theta2_dot": _stats(sw.theta2_dot),
           "conditioning": rep.as_dict(), "problems": rep.problems()}
    if bag.has(SWING_TRUTH):
        tr = bag.joint_state(SWING_TRUTH, list(SWING_NAMES))
        ok = np.isfinite(tr.t)
        if ok.sum() >= 2:
            res["rms_error_vs_ground_truth"] = {
                n: float(np.sqrt(np.nanmean((getattr(sw, n) - np.interp(sw.t, tr.t[ok], tr.position[ok, i])) ** 2)))
                for i, n in enumerate(("theta1", "theta2", "rope_length"))}
    if out:
        write_swing_estimate(out, sw, bag.description_yaml, overwrite=overwrite)
        res["out"] = str(out)
    return res


def write_swing_estimate(path, sw: SwingAngles, description_yaml: str | None = None,
                         overwrite: bool = False) -> None:
    """Write ``/crane/swing_estimate`` (names theta1, theta2, rope_length; position + velocity)."""
    from ...bags import BagWriter

    with BagWriter(path, overwrite=overwrite) as w:
        if description_yaml:
            w.write_description(description_yaml)
        w.write_joint_states(SWING_ESTIMATE, sw.t, SWING_NAMES, position=sw.position,
                             velocity=sw.velocity)


def dataset(bag, description, options: dict | None = None) -> Dataset:
    """Crane dataset from a bag (``/crane/joint_states`` + the two motion-capture poses)."""
    for topic, typ in ((JOINT_STATES, JOINT_STATE), (TIP_POSE, POSE), (PAYLOAD_POSE, POSE)):
        bag.require(topic, typ)
    js = bag.joint_state(JOINT_STATES, list(JOINTS))
    for name, arr in (("position", js.position), ("effort", js.effort)):
        if not np.isfinite(arr).any(axis=0).all():
            raise CablelabError(f"{bag.path}: {JOINT_STATES} has no {name} values for some of "
                                f"{', '.join(JOINTS)}")
    tip = bag.pose(TIP_POSE)
    pay = bag.pose(PAYLOAD_POSE)
    if tip.t.shape != pay.t.shape:
        raise CablelabError(f"{bag.path}: {TIP_POSE} has {tip.t.size} poses, {PAYLOAD_POSE} "
                            f"{pay.t.size}; expected one payload pose per tip pose")
    return dataset_from_arrays(js.t, js.position, js.effort, tip.t, tip.position, pay.position,
                               description, options, source=str(bag.path))


def baseline(description) -> tuple[str, ...]:
    """Nominal model: the rigid body (+ the counterbalance when the description knows one)."""
    c = description.crane if description is not None else None
    if c is not None and c.counterbalance is not None:
        return ("crane_rigid_body", "counterbalance")
    return ("crane_rigid_body",)


def candidates(description) -> tuple[str, ...]:
    """Effects a crane diagnosis tries (CONTRACT sec. 4)."""
    return ("counterbalance", "base_tilt", "joint_viscous_friction", "joint_coulomb_friction",
            "torque_sensor_offset", "time_delay")


def _check_joint_names(bag, series) -> list[str]:
    """Before a fit: the joint states name slew, luff and hoist."""
    from ...bagcheck import check_names

    if JOINT_STATES in series:
        check_names(bag, JOINT_STATES, series[JOINT_STATES].names, JOINTS, plant="crane")
    return []


#: the measured boom tip may differ from the one of the joint angles by this share of the boom
#: length (motion-capture marker offset, boom bending) before the angles are called contradictory
TIP_TOLERANCE = 0.25
#: a pose that moves less than this (m) over the whole record is frozen
FROZEN_SPAN_M = 1e-6


def check_bag(bag, desc, options, series) -> list[str]:
    """Before a fit or an estimate: the joint names (slew, luff, hoist), then contradicting
    measurements (:func:`check_measurements`)."""
    _check_joint_names(bag, series)
    if JOINT_STATES not in series or desc.crane is None:
        return []
    return check_measurements(bag, desc.crane.boom_length, series[JOINT_STATES], series.get(TIP_POSE),
                              series.get(PAYLOAD_POSE))


def check_measurements(bag, boom_length: float, js, tip=None, payload=None) -> list[str]:
    """Joint angles against the motion capture, and a payload that moves with the crane.

    * slew / luff angles in degrees: the boom tip of the recorded angles (002 eq. A.3) is far
      (more than :data:`TIP_TOLERANCE` x the boom length, median) from the measured tip, and the
      same angles read as degrees put it three times closer -> error; far without that
      explanation -> warning. Without a usable tip pose: a luff angle beyond +-pi/2 (the boom
      would point below the horizon behind the slew axis) with values of more than 3 -> error.
    * a payload pose that never moves (span below :data:`FROZEN_SPAN_M`) while slew, luff or
      hoist move -> error (the swing angles would be the boom's motion, not a swing).
    """
    from .kinematics import boom_tip

    names = list(js.names)
    col = {j: names.index(j) for j in JOINTS if j in names}
    if "slew" not in col or "luff" not in col:
        return []
    q = js.position
    alpha, beta = q[:, col["slew"]], q[:, col["luff"]]
    ok = np.isfinite(js.t) & np.isfinite(alpha) & np.isfinite(beta)
    if ok.sum() < 10:
        return []
    t, alpha, beta = js.t[ok], alpha[ok], beta[ok]
    warnings = []
    degrees_hint = ("slew and luff must be in rad (import: --map position.slew=0.0174533*COLUMN, "
                    "the same for luff)")
    checked = False
    if tip is not None and np.isfinite(tip.position).all(axis=1).sum() >= 10:
        tok = np.isfinite(tip.position).all(axis=1) & np.isfinite(tip.t)
        order = np.argsort(tip.t[tok])
        tt, tp = tip.t[tok][order], tip.position[tok][order]
        inside = (t >= tt[0]) & (t <= tt[-1])
        if inside.sum() >= 10:
            meas = np.stack([np.interp(t[inside], tt, tp[:, k]) for k in range(3)], axis=1)
            e_rad = float(np.median(np.linalg.norm(
                boom_tip(alpha[inside], beta[inside], boom_length) - meas, axis=1)))
            e_deg = float(np.median(np.linalg.norm(
                boom_tip(np.deg2rad(alpha[inside]), np.deg2rad(beta[inside]), boom_length) - meas, axis=1)))
            checked = True
            if e_rad > TIP_TOLERANCE * boom_length:
                if e_deg < e_rad / 3:
                    raise CablelabError(
                        f"{bag.path}: {JOINT_STATES}: slew / luff look like degrees (luff "
                        f"{np.min(beta):.3g}..{np.max(beta):.3g}): the boom tip they give is "
                        f"{e_rad:.3g} m from {TIP_POSE} (median), read as degrees {e_deg:.3g} m; "
                        f"{degrees_hint}")
                warnings.append(
                    f"{JOINT_STATES}: the boom tip of the slew / luff angles is {e_rad:.3g} m (median) "
                    f"from {TIP_POSE} with a boom of {boom_length:g} m: the angles, the boom length "
                    f"of the description or the tip's motion capture are wrong")
    if not checked and np.max(np.abs(beta)) > max(np.pi / 2, 3.0):
        raise CablelabError(
            f"{bag.path}: {JOINT_STATES}: luff reaches {np.max(np.abs(beta)):.4g}, beyond +-pi/2 rad; "
            f"the angles look like degrees: {degrees_hint}")
    if payload is not None:
        pok = np.isfinite(payload.position).all(axis=1)
        if pok.sum() >= 10:
            span = float(np.max(np.ptp(payload.position[pok], axis=0)))
            moves = {j: float(np.nanmax(q[:, c]) - np.nanmin(q[:, c])) for j, c in col.items()}
            moving = {j: v for j, v in moves.items() if v > 0.01}   # rad or m
            if span < FROZEN_SPAN_M and moving:
                what = ", ".join(f"{j} by {v:.3g} {'m' if j == 'hoist' else 'rad'}" for j, v in moving.items())
                raise CablelabError(
                    f"{bag.path}: {PAYLOAD_POSE} is frozen at {np.round(payload.position[pok][0], 4).tolist()} "
                    f"for the whole recording while the crane moves ({what}): the payload's motion "
                    f"capture did not track it, no swing can be measured")
    return warnings


CRANE = register_plant(Plant(
    name="crane",
    topics=((JOINT_STATES, JOINT_STATE), (TIP_POSE, POSE), (PAYLOAD_POSE, POSE)),
    dataset=dataset,
    baseline=baseline,
    candidates=candidates,
    channels_doc="slew, luff torque (N m), hoist force (N)",
    simulate=free_run_compare,
    simulation_fit=fit_free_run,
    section=parse_section,
    contract_topics={
        JOINT_STATES: JOINT_STATE,
        TIP_POSE: POSE,
        PAYLOAD_POSE: POSE,
        "/crane/reference": "trajectory_msgs/msg/JointTrajectory",
        "/crane/effort_commands": "std_msgs/msg/Float64MultiArray",
        "/crane/swing_estimate": JOINT_STATE,
        "/crane/ground_truth/swing": JOINT_STATE,
    },
    joint_topic=JOINT_STATES,
    joints=JOINTS,
    capabilities=frozenset({"joint_actuators"}),
    estimate=estimate_bag,
    check_bag=check_bag,
    channels=JOINTS,
    markers=lambda bag, desc: _bag_markers(bag, desc),
    topic_names=lambda desc: {JOINT_STATES: list(JOINTS), **{t: ["theta1", "theta2", "rope_length"] for t in
                                                          ("/crane/swing_estimate", "/crane/ground_truth/swing")}},
))


def _bag_markers(bag, desc):
    from .markers import bag_markers

    return bag_markers(bag, desc)


# ----------------------------------------------------------------------------- experiment design
#: the lab crane's safe envelope for designed excitations (slew rad, luff rad, hoist m): the
#: range the simulated crane's default excitation spans (sim.reference_trajectory) widened to
#: what its drives reach without saturating (sim.CraneTruth.effort_limit)
EXCITE_LOWER = (-1.0, 0.2, 0.3)
EXCITE_UPPER = (1.0, 1.0, 1.0)
EXCITE_SPEED = (0.6, 0.4, 0.6)
EXCITE_ACCEL = (1.0, 0.8, 3.0)


def excite_limits(description):
    from ...excite import Limits

    return Limits(JOINTS, np.array(EXCITE_LOWER), np.array(EXCITE_UPPER), np.array(EXCITE_SPEED),
                  np.array(EXCITE_ACCEL))


def motion_dataset(t, q, qd, qdd, description) -> Dataset:
    """The crane dataset of a motion that follows the reference exactly, payload hanging still
    (swing angles 0): the regressor the effects see, outputs zero."""
    n = len(t)
    z = np.zeros((n, 2))
    q5, qd5, qdd5 = (np.column_stack([a, z]) for a in (q, qd, qdd))
    g = description.gravity if description is not None else STANDARD_GRAVITY
    return Dataset(plant="crane", t=np.asarray(t, float), y=np.zeros((n, 3)), channels=JOINTS,
                   units=("N m", "N m", "N"),
                   signals={"q": q5, "qd": qd5, "qdd": qdd5, "Y": regressor(q5, qd5, qdd5, g),
                            "boom_length": description.crane.boom_length if description is not None else 1.0},
                   actuators=JOINTS, act_vel=qd5[:, :3],
                   act_units=(("N m", "rad"), ("N m", "rad"), ("N", "m")),
                   description=description, source="designed motion")


def _register_exciter():
    from ...excite import Exciter, register_exciter

    register_exciter("crane", Exciter(limits=excite_limits, motion_dataset=motion_dataset,
                                      reference_topic=REFERENCE, base_hz=0.1, harmonics=6))


_register_exciter()
