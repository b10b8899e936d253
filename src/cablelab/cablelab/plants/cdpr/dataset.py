"""The CDPR dataset: a contract bag read into arrays (:func:`load_arrays`) and the workbench
:class:`~cablelab.dataset.Dataset` (output channels = the cable wrench W t, 6 channels, see
:mod:`cablelab.plants.cdpr.effects`), and the checks of a bag before a fit.

Bag topics (CONTRACT section 2): ``/cdpr/cable_tensions`` (dynamometers), ``/cdpr/joint_states``
(motor angles, rates, torques), ``/cdpr/reference`` (desired pose, twist, acceleration; 001's
real-time choice for W), ``/cdpr/platform_pose`` (measured pose, used when there is no
reference or when asked), ``/cdpr/ground_truth/payload`` (simulation truth, only for the error).
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from ...errors import CablelabError
from ...dataset import Dataset
from ...plant_interface import DatasetOptions
from ...rotations import quat_to_matrix, xyzw_to_wxyz
from ...timebase import interp_columns
from .geometry import cable_geometry, check_pulley_radius, wrench_matrix
from .options import CdprOptions

from .topics import (CABLE_TENSIONS as TENSIONS, GROUND_TRUTH_PAYLOAD as TRUTH,
                     JOINT_STATES as JOINTS, PLATFORM_POSE as POSE, REFERENCE)
CHANNELS = ("Fx", "Fy", "Fz", "Mx", "My", "Mz")
UNITS = ("N", "N", "N", "N m", "N m", "N m")


@dataclass
class CdprArrays:
    """A CDPR bag as arrays on the time base of the tension source (N samples, n cables).

    Attributes:
        t: (N,) s; tensions: (N, n) raw tensions, N (dynamometer, or R/r * motor torque);
        motor_velocity: (N, n) rad/s; position (N, 3), R (N, 3, 3) or None (level), acc (N, 3):
        the pose used for W and its acceleration; velocity (N, 3); truth_mass: kg or None;
        truth_com: (2,) or None; source: "dynamometer", "motor" or "both" (tensions from the
        dynamometers, motor torques kept in ``motor_effort`` for the torque balance); scale: R/r (1/m).
    """

    t: np.ndarray
    tensions: np.ndarray
    motor_velocity: np.ndarray
    motor_effort: np.ndarray
    position: np.ndarray
    R: np.ndarray | None
    acc: np.ndarray
    velocity: np.ndarray
    truth_mass: float | None
    truth_com: np.ndarray | None
    source: str
    scale: float


def _finite_rows(*arrays) -> np.ndarray:
    ok = None
    for a in arrays:
        a = np.asarray(a)
        f = np.isfinite(a.reshape(a.shape[0], -1)).all(1)
        ok = f if ok is None else ok & f
    return ok


def load_arrays(bag, description, tensions: str = "dynamometer", pose: str = "desired",
                derived_velocity=()) -> CdprArrays:
    """Read a contract bag into :class:`CdprArrays` (one-line errors naming the topic).

    Args:
        tensions: "dynamometer" (``/cdpr/cable_tensions`` effort), "motor" (``/cdpr/joint_states``
            effort times R/r, 001 sec. V-B) or "both" (dynamometers for the wrench, and the
            per-winch torque balance against the motor torques, :func:`dataset_from_arrays`).
        pose: "desired" (``/cdpr/reference``; falls back to the measured pose when absent) or
            "measured" (``/cdpr/platform_pose``).
        derived_velocity: winch names whose measured velocity contradicts their angle
            (:func:`cablelab.bagcheck.velocity_checks`): derived from the angles instead.
    """
    c = description.cdpr
    if c is None:
        raise CablelabError(f"{bag.path}: plant description has no 'cdpr' section")
    n = len(c.cables)
    scale = c.gear_ratio / c.drum_radius
    if tensions not in ("dynamometer", "motor", "both"):
        raise CablelabError(f"--tensions {tensions!r}: expected dynamometer, motor or both")
    if not bag.has(JOINTS):
        raise CablelabError(f"{bag.path}: topic {JOINTS} is not in the bag")
    js = bag.joint_state(JOINTS, [f"winch_{i}" for i in range(1, n + 1)])
    if tensions in ("dynamometer", "both"):
        if not bag.has(TENSIONS):
            raise CablelabError(f"{bag.path}: topic {TENSIONS} (dynamometers) is not in the bag; "
                                "use --tensions motor")
        ts = bag.joint_state(TENSIONS, [f"cable_{i}" for i in range(1, n + 1)])
        t, tens = ts.t, ts.effort
        what = f"{TENSIONS} effort"
    else:
        t, tens = js.t, js.effort * scale
        what = f"{JOINTS} effort"
    ok = _finite_rows(t, tens)
    if ok.sum() < 2:
        raise CablelabError(f"{bag.path}: {what} has no complete samples of {n} cables")
    t, tens = t[ok], tens[ok]
    t, first = np.unique(t, return_index=True)       # sorted, repeated stamps dropped
    tens = tens[first]
    jok = _finite_rows(js.t, js.position)
    jok &= np.r_[True, np.diff(js.t) > 0] if len(js.t) else jok     # repeated stamps
    qd = js.velocity
    derived = np.gradient(js.position[jok], js.t[jok], axis=0) if jok.sum() > 1 else qd[jok]
    if not np.isfinite(qd[jok]).all():          # empty velocity: derive from the angles
        qd = derived
    else:
        qd = qd[jok].copy()
        distrusted = [i for i, nm in enumerate(js.names) if nm in set(derived_velocity)]
        qd[:, distrusted] = derived[:, distrusted]
    motor_velocity = interp_columns(t, js.t[jok], qd)
    eok = jok & _finite_rows(js.effort)
    motor_effort = interp_columns(t, js.t[eok], js.effort[eok]) if eok.sum() > 1 else np.full_like(tens, np.nan)
    if tensions == "both" and eok.sum() < 2:
        raise CablelabError(f"{bag.path}: --tensions both: {JOINTS} has no motor torques (effort); "
                            "use --tensions dynamometer")
    R = None
    if pose == "desired" and bag.has(REFERENCE):
        ref = bag.multidof_trajectory(REFERENCE)
        rok = _finite_rows(ref.t, ref.position)
        if rok.sum() < 2:
            raise CablelabError(f"{bag.path}: {REFERENCE} has no desired positions")
        tr = ref.t[rok]
        position = interp_columns(t, tr, ref.position[rok])
        acc = ref.linear_acceleration[rok]
        acc = interp_columns(t, tr, acc) if np.isfinite(acc).all() else np.zeros_like(position)
        vel = ref.linear_velocity[rok]
        vel = interp_columns(t, tr, vel) if np.isfinite(vel).all() else np.gradient(position, t, axis=0)
        quat = ref.quaternion[rok]
    elif bag.has(POSE):
        ps = bag.pose(POSE)
        pok = _finite_rows(ps.t, ps.position)
        if pok.sum() < 2:
            raise CablelabError(f"{bag.path}: {POSE} has no positions")
        position = interp_columns(t, ps.t[pok], ps.position[pok])
        vel = np.gradient(position, t, axis=0)
        acc = np.gradient(vel, t, axis=0)
        quat, tr = ps.quaternion[pok], ps.t[pok]
    else:
        want = REFERENCE if pose == "desired" else POSE
        raise CablelabError(f"{bag.path}: no platform pose: topic {want} is not in the bag")
    if np.isfinite(quat).all() and not np.allclose(quat[:, :3], 0.0, atol=1e-9):
        q = interp_columns(t, tr, xyzw_to_wxyz(quat))
        R = quat_to_matrix(q)
    truth_m, truth_c = None, None
    if bag.has(TRUTH):
        tru = bag.inertia(TRUTH)
        if np.isfinite(tru.m).any():
            truth_m = float(np.nanmedian(tru.m))
            truth_c = np.nanmedian(tru.com[:, :2], axis=0)
    return CdprArrays(t, tens, motor_velocity, motor_effort, position, R, acc, vel, truth_m,
                      truth_c, tensions, scale)


def _regimes(arr: CdprArrays) -> dict:
    v = arr.velocity
    vz = np.abs(v[:, 2])
    vh = np.linalg.norm(v[:, :2], axis=1)
    lab = np.where(vz > 0.02, "vertical motion", np.where(vh > 0.02, "horizontal travel", "at rest"))
    return {"motion": lab}


def model_wrench_matrix(W: np.ndarray, S: np.ndarray, description) -> np.ndarray:
    """The wrench matrix of the nominal model, (N, 6, n): Model II at the described sheave radius
    ``W_I + r_p S`` (exact at r_p = the description's, 001 eq. 6-9), else Model I. Cable-side
    terms (dynamometer offsets, winch friction) reach the wrench through it."""
    r = description.cdpr.pulley_radius if description is not None and description.cdpr is not None else 0.0
    return W + r * S if r > 0 else W


def torque_balance(arr: CdprArrays) -> np.ndarray:
    """(N, n) per-winch torque balance, N: ``(R/r) tau_i - d_i``, the motor torque tau_i (N m)
    brought to the cable side minus the dynamometer reading d_i (N).

    With 001 eq. 15 (motor torque = (r/R) t_i + winch friction, motor side) and a dynamometer
    reading d_i = t_i + b_i, the unknown tension t_i cancels:
    ``(R/r) tau_i - d_i = (R/r) (F_c,i sign(qdot_i) + F_v,i qdot_i) - b_i`` (+ noise): each
    winch's friction and each dynamometer offset on a channel of its own."""
    return arr.scale * arr.motor_effort - arr.tensions


def balance_mask(qd: np.ndarray, floor: float | np.ndarray = 0.0) -> np.ndarray:
    """(N, n) 1.0 where winch i is outside its zero-speed zone (:mod:`cablelab.velocity`), else
    0.0: a stopped winch holds its cable with any torque inside its stiction band, and the sign
    of its measured speed is noise there, so its torque balance says nothing at rest."""
    from ...velocity import zero_speed_zone

    zone = zero_speed_zone(qd, floor)
    return (np.abs(qd) >= zone[None, :]).astype(float)


def dataset_from_arrays(arr: CdprArrays, description, source: str = "data",
                        decimate: int = 1) -> Dataset:
    """Workbench dataset (Model I wrench channels; see :mod:`cablelab.plants.cdpr.effects`).

    ``arr.source == "both"`` (the bag has dynamometers and motor torques): the six wrench channels
    W d from the dynamometers, plus one torque-balance channel per winch (:func:`torque_balance`,
    N), set to 0 (measurement and every regressor) while that winch is in its zero-speed zone
    (:func:`balance_mask`). The wrench alone sees eight dynamometer offsets only through W, whose
    two-dimensional null space (internal forces) is invisible at each pose; the balance channels
    see each offset and each winch's friction on its own channel. Samples with a winch at rest are
    still left out by the workbench (:func:`cablelab.velocity.exclude_zero_speed`): kept, their
    static poses made the sheave radius and the mass indistinguishable in the wrench (case 3016:
    r_p fitted right but rejected as confounded with m, correlation 0.998)."""
    c = description.cdpr
    k = max(1, int(decimate))
    sl = slice(None, None, k)
    pos, R = arr.position[sl], None if arr.R is None else arr.R[sl]
    check_pulley_radius(c.exit_points, c.anchor_points, pos, R, c.pulley_radius, c.swivel_axes)
    geom = cable_geometry(c.exit_points, c.anchor_points, pos, R, 0.0, c.swivel_axes)
    W = wrench_matrix(geom)
    t = arr.tensions[sl]
    y = np.einsum("tij,tj->ti", W, t)
    r_ref = c.pulley_radius if c.pulley_radius > 0 else 0.15
    W2 = wrench_matrix(cable_geometry(c.exit_points, c.anchor_points, pos, R, r_ref, c.swivel_axes))
    S = (W2 - W) / r_ref                               # d(W)/d(r_p), motion side
    slope = np.einsum("tij,tj->ti", S, t)
    W_model = model_wrench_matrix(W, S, description)
    n = t.shape[1]
    act_scale = np.full(n, arr.scale if arr.source in ("motor", "both") else 1.0)
    unit = "N m" if arr.source in ("motor", "both") else "N"
    qd = arr.motor_velocity[sl]
    sig = {"tensions": t, "position": pos, "R": R, "acc": arr.acc[sl], "W": W, "pulley_slope": slope,
           "pulley_S": S, "act_scale": act_scale, "velocity": arr.velocity[sl]}
    channels, units = CHANNELS, UNITS
    act_map = W_model * act_scale[None, None, :]
    # the wrench channels mix the cables' independent sensors (dynamometers or motor torques,
    # whose noise differs from cable to cable): the fit whitens each sample with W diag(v) W^T
    noise_map = W
    if arr.source == "both":
        mask = balance_mask(qd)
        bal = torque_balance(arr)[sl] * mask
        y = np.concatenate([y, bal], axis=1)
        channels = CHANNELS + tuple(f"balance_{i}" for i in range(1, n + 1))
        units = UNITS + ("N",) * n
        act_map = np.concatenate([np.zeros_like(W), _balance_map(mask, act_scale)], axis=1)
        # the workbench still leaves samples with a winch at rest out (as for the dynamometers
        # alone): at static poses the sheave radius and the mass act alike on the wrench
        sig.update(balance_mask=mask)
        noise_map = None      # (the balance channels are weighted each by its own noise level)
    return Dataset(
        plant="cdpr", t=arr.t[sl], y=y, channels=channels, units=units, signals=sig,
        actuators=tuple(f"winch_{i}" for i in range(1, n + 1)), act_vel=qd,
        act_map=act_map, act_units=((unit, "rad"),) * n,
        regimes={k2: v[sl] for k2, v in _regimes(arr).items()},
        inputs={"vertical acceleration": arr.acc[sl, 2], "speed": np.linalg.norm(arr.velocity[sl], axis=1)},
        description=description, source=source, noise_map=noise_map)


def _balance_map(mask: np.ndarray, act_scale: np.ndarray) -> np.ndarray:
    """(N, n, n) motor-side winch effort -> torque-balance channels: diag(mask_i R/r)."""
    n = mask.shape[1]
    out = np.zeros(mask.shape + (n,))
    idx = np.arange(n)
    out[:, idx, idx] = mask * act_scale[None, :]
    return out


def remeasure(ds: Dataset, shifted: Dataset) -> Dataset:
    """``time_delay`` hook: the measured tensions at t belong to the pose at t - tau, so the wrench
    they exert is ``W(p(t - tau)) t_meas(t)`` (001 eq. 4 at the shifted pose; the pulley slope
    likewise). ``shifted`` holds W and the slope matrix at t - tau; the tensions stay unshifted."""
    t = ds.signals["tensions"]
    sig = dict(shifted.signals, tensions=t,
               pulley_slope=np.einsum("tij,tj->ti", shifted.signals["pulley_S"], t))
    y = np.einsum("tij,tj->ti", shifted.signals["W"], t)
    if "balance_mask" in ds.signals:
        # torque balance: measured against measured, no pose in it; its rest mask stays the
        # measurement's (the winch speeds and the map follow t - tau)
        mask = ds.signals["balance_mask"]
        sig["balance_mask"] = mask
        y = np.concatenate([y, ds.y[:, y.shape[1]:]], axis=1)
        amap = shifted.act_map.copy()
        amap[:, y.shape[1] - mask.shape[1]:, :] = _balance_map(mask, ds.signals["act_scale"])
        return shifted.replace(y=y, signals=sig, act_map=amap)
    return shifted.replace(y=y, signals=sig)


def dataset(bag, description, options: DatasetOptions) -> Dataset:
    """Plant hook of the workbench: the bag's CDPR dataset (the plant options
    :class:`~.options.CdprOptions` ``tensions`` and ``pose``, and ``conditioning.decimate``)."""
    own = options.plant_options(CdprOptions)
    arr = load_arrays(bag, description, own.tensions, own.pose, options.derived_velocity.get(JOINTS, ()))
    return dataset_from_arrays(arr, description, str(bag.path), options.conditioning.decimate or 1)


def check_bag(bag, desc, options: DatasetOptions, series) -> list[str]:
    """Before a fit: one winch and one cable per described cable, no cable that pushes, tensions
    that are not all zero, and a geometry that can hold the platform (:func:`check_geometry`)."""
    from ...bagcheck import check_names, negative_tension_warnings

    warnings = []
    n = len(desc.cdpr.cables) if desc.cdpr is not None else None
    own = options.plant_options(CdprOptions)
    source = own.tensions
    for topic, prefix, noun in ((JOINTS, "winch", "winches"), (TENSIONS, "cable", "cables")):
        s = series.get(topic)
        if s is None or n is None:
            continue
        check_names(bag, topic, s.names, [f"{prefix}_{i}" for i in range(1, n + 1)], exact=True,
                    noun=noun, described="cables")
        if topic == TENSIONS and source in ("dynamometer", "both"):
            warnings.extend(negative_tension_warnings(s.effort, s.names, topic))
        if (topic == TENSIONS) == (source in ("dynamometer", "both")):
            _refuse_zero_load(bag, topic, s.effort, "tension" if topic == TENSIONS else "motor torque")
    if desc.cdpr is not None:
        pose = series.get(REFERENCE) if own.pose == "desired" else None
        pose = pose if pose is not None else series.get(POSE)
        check_geometry(bag, desc.cdpr, None if pose is None else pose.position)
    return warnings


def _refuse_zero_load(bag, topic: str, effort, what: str) -> None:
    """All-zero (or empty) load measurements give a mass of 0 kg: refuse them."""
    e = np.asarray(effort, dtype=float)
    fin = e[np.isfinite(e)]
    if fin.size and not np.any(fin != 0.0):
        raise CablelabError(f"{bag.path}: {topic}: every {what} sample is exactly 0 (sensor not "
                            f"connected or not recorded?); no load is measured, so no mass can be "
                            f"estimated")


def check_geometry(bag, c, positions=None) -> None:
    """One-line errors for a description whose geometry cannot hold or measure the platform:
    two cables with the same exit and anchor points, a force map (the force rows of the wrench
    matrix) of rank below min(3, n) at the recorded poses, or poses where no cable pulls up
    (every exit point at or below its anchor point: the cables cannot carry the weight).

    Args:
        c: the ``cdpr`` section; positions: (N, 3) recorded platform positions, or None (then
            only the coincident cables are checked: the poses decide the rest).
    """
    A, B = c.exit_points, c.anchor_points
    n = len(A)
    size = max(float(np.ptp(A, axis=0).max()), 1e-3)
    for i in range(n):
        for j in range(i + 1, n):
            if np.linalg.norm(A[i] - A[j]) < 1e-6 * size and np.linalg.norm(B[i] - B[j]) < 1e-6 * size:
                raise CablelabError(
                    f"{bag.path}: plant description: cables {i + 1} and {j + 1} have the same exit "
                    f"point {A[i].tolist()} and anchor point {B[i].tolist()} (two cables cannot run "
                    f"along one line; a copy-paste error in the description?)")
    P = None if positions is None else np.asarray(positions, dtype=float)
    if P is not None:
        P = P[np.all(np.isfinite(P), axis=1)]
        P = P[:: max(1, len(P) // 200)]
    if P is None or not len(P):
        return
    geom = cable_geometry(A, B, P, None, 0.0, c.swivel_axes)
    u = geom.directions                                          # (N, n, 3) anchor -> exit
    up = u[:, :, 2].max(axis=1)
    if np.any(up <= 1e-9):
        k = int(np.argmin(up))
        raise CablelabError(
            f"{bag.path}: plant description: at the platform position {np.round(P[k], 3).tolist()} "
            f"no cable pulls up (every exit point is at or below its anchor point: lowest exit "
            f"point z = {A[:, 2].min():.3g} m, highest {A[:, 2].max():.3g} m); the cables cannot carry "
            f"the weight: check the z of the exit points (world frame, z up)")
    sv = np.linalg.svd(u.transpose(0, 2, 1), compute_uv=False)    # (N, 3) of the force map
    need = min(3, n)
    rel = sv[:, need - 1] / np.maximum(sv[:, 0], 1e-300)
    if np.any(rel < 1e-6):
        k = int(np.argmin(rel))
        raise CablelabError(
            f"{bag.path}: plant description: the cable directions at the platform position "
            f"{np.round(P[k], 3).tolist()} span fewer than {need} dimensions (singular wrench "
            f"matrix: all cables in one line or plane); the forces cannot be resolved, check the "
            f"exit and anchor points")
