"""The crane dataset (002; CONTRACT sections 2-3, prefix ``/crane``): bag -> Dataset, and the
checks of a bag before a fit.

Channels slew torque (N m), luff torque (N m), hoist force (N) from ``/crane/joint_states``;
q = [alpha, beta, d, theta1, theta2] with alpha, beta, d from the joint states and theta1, theta2
from the motion-capture poses (interpolated at the joint-state stamps), conditioned by
:func:`cablelab.conditioning.condition_motion` (unwrap, uniform grid, zero-phase Butterworth,
central differences), and the signal ``Y`` = the 5 x 9 regressor per sample.
"""
from __future__ import annotations

import dataclasses

import numpy as np

from ...conditioning import condition_motion
from ...errors import CablelabError
from ...dataset import STANDARD_GRAVITY, Dataset
from ...plant_interface import DatasetOptions
from .dynamics_generated import regressor
from .model import JOINTS
from .options import CraneOptions
from .swing import estimate_swing

from .topics import JOINT_STATE, JOINT_STATES, PAYLOAD_POSE, POSE, TIP_POSE
SWING_NAMES = ("theta1", "theta2", "rope_length")
#: default low-pass cut-off of the crane's identification equations, Hz (when --cutoff is not
#: given). The payload swings at sqrt(g / d) / (2 pi) ~ 0.6-1 Hz and the excitation stays below
#: ~0.5 Hz, while motion-capture noise is differentiated twice for the swing accelerations: the
#: generic fs / 10 (10 Hz at 100 Hz) lets 1 mm of noise become metres per second squared (002 sec.
#: 5.1.3 chose its filters case by case; this is the case for the crane). By default the positions
#: are filtered at it and differentiated; the plant option ``crane_filter="parallel"``
#: (:mod:`.options`) takes the derivatives at fs / 10 and low-passes the efforts and every
#: regressor column at this cut-off alike (:mod:`cablelab.parallel_filter`). Filtering the
#: positions alone attenuates the swing's 1.5-3 Hz content (twice the swing frequency, in the
#: centripetal and Coriolis terms) in the regressor but not in the efforts: a model error of 2-5 %
#: of the torques that moved 0.2 % of the payload mass into the hoist and luff offsets (2-3 % of
#: them) on designed runs. The parallel filter is not the default, though its equations are the
#: exact ones: it changes the fit's channel noise weights (1 / residual spread). The positions
#: filter leaves the efforts' broadband sensor noise in the residual, which sets the weights; the
#: parallel filter removes it above the cut-off, and the slew channel's residual is then the
#: in-band noise of the swing accelerations (motion capture differentiated twice): the slew channel,
#: the one that tells the counterbalance's inertia from I_tot, loses half its weight or more and the
#: counterbalance's spread over noise grows (bench/cases_crane.py --filter-noise; docs/benchmarks.md).
CRANE_CUTOFF_HZ = 3.0

__all__ = ["check_bag", "check_measurements", "dataset", "dataset_from_arrays"]


def _swing_regimes(theta1: np.ndarray, theta2: np.ndarray) -> np.ndarray:
    amp = np.hypot(theta1, theta2)
    edges = np.quantile(amp, [1 / 3, 2 / 3])
    labels = np.array([f"swing < {edges[0]:.2g} rad", f"swing {edges[0]:.2g}-{edges[1]:.2g} rad",
                       f"swing > {edges[1]:.2g} rad"])
    return labels[np.searchsorted(edges, amp)]


def dataset_from_arrays(t, q_joints, effort, t_mocap, tip, payload, description,
                        options: DatasetOptions | None = None, *, source: str = "data") -> Dataset:
    """Crane dataset from raw arrays.

    Args:
        t: (N,) joint-state stamps, s. q_joints: (N, 3) [alpha rad, beta rad, d m].
        effort: (N, 3) [slew N m, luff N m, hoist N].
        t_mocap, tip, payload: (M,), (M, 3), (M, 3) motion capture (NaN rows = dropouts).
        description: :class:`~cablelab.description.Description` with a ``crane`` section.
        options: the conditioning and the crane's own options (:class:`.options.CraneOptions`:
            ``crane_filter``); defaults when None.
    """
    opts = (options or DatasetOptions()).conditioning
    t = np.asarray(t, dtype=float)
    parallel = None
    if opts.cutoff_hz is None:
        fs = 1.0 / float(np.median(np.diff(t[np.isfinite(t)]))) if np.isfinite(t).sum() > 1 else 0.0
        mode = (options or DatasetOptions()).plant_options(CraneOptions).crane_filter
        if mode == "parallel" and fs / 10.0 > CRANE_CUTOFF_HZ:   # derivatives at fs / 10, both
            # sides of the fit at CRANE_CUTOFF_HZ
            opts, parallel = dataclasses.replace(opts, cutoff_hz=fs / 10.0, effort_cutoff_hz=None), CRANE_CUTOFF_HZ
        else:
            opts = dataclasses.replace(opts, cutoff_hz=CRANE_CUTOFF_HZ)
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
    # effort and the sign of a filtered, quantized encoder velocity is noise. The zones come from
    # the drives' speeds in the efforts' band; they are applied before the parallel filter is
    # declared, so without exclude_zero_speed's rest guard: the crane's three drives seldom all
    # move at once, and guarding every stop of any drive by half a filter period left 16 % of a
    # 30 s chirp record (468 of 2900 samples)
    from ...velocity import exclude_zero_speed, position_quantum, speed_resolution

    ok_q = q_joints[ok]
    floor = np.array([speed_resolution(position_quantum(ok_q[:, j]), parallel or c["cutoff_hz"]) for j in range(3)])
    if parallel:
        from ...parallel_filter import edge_mask, parallel_filter

        ds = ds.replace(signals={**ds.signals, "rest_velocity": parallel_filter(qd[:, :3], ds.t, parallel)})
    ds = exclude_zero_speed(ds, floor=floor)
    if parallel:
        ds = ds.replace(y=parallel_filter(ds.y, ds.t, parallel), parallel_hz=parallel,
                        valid=ds.valid & edge_mask(ds.t, parallel))
    return ds


def dataset(bag, description, options: DatasetOptions) -> Dataset:
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
