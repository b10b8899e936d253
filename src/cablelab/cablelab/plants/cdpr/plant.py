"""The suspended CDPR as a workbench plant, and offline payload estimation from a bag (001).

Geometry, estimation, control and trajectory live in the ``cdpr_*`` modules next to this one;
this module reads a contract bag into arrays (:func:`load_arrays`), builds the workbench
:class:`~cablelab.dataset.Dataset` (output channels = the cable wrench W t, 6 channels, see
:mod:`cablelab.plants.cdpr.effects`) and runs the offline estimate of ``cablelab estimate``
(:func:`estimate_bag`): mass and CoM per sample, vectorised over the whole bag (001 eq. 12-13).

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
from ...rotations import quat_to_matrix, xyzw_to_wxyz
from ...registry import Plant, register_plant
from .description import dump_section, parse_section
from .estimation import mass_com, mass_com_batch
from .geometry import cable_geometry, check_pulley_radius, wrench_matrix

JOINT_STATE = "sensor_msgs/msg/JointState"
TENSIONS = "/cdpr/cable_tensions"
JOINTS = "/cdpr/joint_states"
REFERENCE = "/cdpr/reference"
POSE = "/cdpr/platform_pose"
TRUTH = "/cdpr/ground_truth/payload"
ESTIMATE = "/cdpr/payload_estimate"
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


def _interp(t_new: np.ndarray, t: np.ndarray, x: np.ndarray) -> np.ndarray:
    """Linear interpolation of (M, k) samples onto t_new (held at the ends)."""
    x = np.asarray(x, float).reshape(len(t), -1)
    if len(t) == len(t_new) and np.array_equal(t, t_new):
        return x
    order = np.argsort(t)
    t, x = t[order], x[order]
    return np.stack([np.interp(t_new, t, x[:, j]) for j in range(x.shape[1])], 1)


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
    motor_velocity = _interp(t, js.t[jok], qd)
    eok = jok & _finite_rows(js.effort)
    motor_effort = _interp(t, js.t[eok], js.effort[eok]) if eok.sum() > 1 else np.full_like(tens, np.nan)
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
        position = _interp(t, tr, ref.position[rok])
        acc = ref.linear_acceleration[rok]
        acc = _interp(t, tr, acc) if np.isfinite(acc).all() else np.zeros_like(position)
        vel = ref.linear_velocity[rok]
        vel = _interp(t, tr, vel) if np.isfinite(vel).all() else np.gradient(position, t, axis=0)
        quat = ref.quaternion[rok]
    elif bag.has(POSE):
        ps = bag.pose(POSE)
        pok = _finite_rows(ps.t, ps.position)
        if pok.sum() < 2:
            raise CablelabError(f"{bag.path}: {POSE} has no positions")
        position = _interp(t, ps.t[pok], ps.position[pok])
        vel = np.gradient(position, t, axis=0)
        acc = np.gradient(vel, t, axis=0)
        quat, tr = ps.quaternion[pok], ps.t[pok]
    else:
        want = REFERENCE if pose == "desired" else POSE
        raise CablelabError(f"{bag.path}: no platform pose: topic {want} is not in the bag")
    if np.isfinite(quat).all() and not np.allclose(quat[:, :3], 0.0, atol=1e-9):
        q = _interp(t, tr, xyzw_to_wxyz(quat))
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
    return Dataset(
        plant="cdpr", t=arr.t[sl], y=y, channels=channels, units=units, signals=sig,
        actuators=tuple(f"winch_{i}" for i in range(1, n + 1)), act_vel=qd,
        act_map=act_map, act_units=((unit, "rad"),) * n,
        regimes={k2: v[sl] for k2, v in _regimes(arr).items()},
        inputs={"vertical acceleration": arr.acc[sl, 2], "speed": np.linalg.norm(arr.velocity[sl], axis=1)},
        description=description, source=source)


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


def dataset(bag, description, options: dict | None = None) -> Dataset:
    """Plant hook of the workbench: the bag's CDPR dataset (options: ``tensions``, ``pose``,
    ``conditioning.decimate``)."""
    options = options or {}
    arr = load_arrays(bag, description, options.get("tensions") or "dynamometer",
                      options.get("pose") or "desired",
                      (options.get("derived_velocity") or {}).get(JOINTS, ()))
    cond = options.get("conditioning")
    return dataset_from_arrays(arr, description, str(bag.path), getattr(cond, "decimate", 1) or 1)


def baseline(description) -> tuple[str, ...]:
    """Nominal model: the payload's weight (001 eq. 13) with the wrench matrix of Model II when the
    description gives a pulley radius, else Model I (point exits)."""
    c = description.cdpr if description is not None else None
    if c is not None and c.pulley_radius > 0:
        return ("cdpr_gravity", "pulley_geometry")
    return ("cdpr_gravity",)


def candidates(description) -> tuple[str, ...]:
    """Effects a diagnosis tries (the friction and offset ones only matter for the tension source
    that carries them; an effect without signal is simply not significant)."""
    return ("pulley_geometry", "platform_inertia", "winch_coulomb_friction",
            "winch_viscous_friction", "tension_sensor_offset", "time_delay")




# ================================================================================ offline estimate

@dataclass
class Estimate:
    """Per-sample payload estimate of a bag (``cablelab estimate``)."""

    t: np.ndarray
    mass: np.ndarray
    com: np.ndarray
    residual: np.ndarray
    effects: tuple
    params: dict
    truth_mass: float | None = None
    truth_com: np.ndarray | None = None

    def summary(self) -> dict:
        """JSON of CONTRACT section 5 (cdpr) + the model, parameters and, when the bag has the
        ground truth, the mass error in %."""
        ok = np.isfinite(self.mass)
        if not ok.any():
            raise CablelabError("no sample gives a finite mass: the cable geometry of the "
                                "description is degenerate at the recorded poses (e.g. an anchor "
                                "closer to its pulley than the sheave radius)")
        m = self.mass[ok]
        out = {"plant": "cdpr", "samples": int(ok.sum()),
               "mass": {"mean": float(m.mean()), "std": float(m.std()),
                        "max_abs_dev": float(np.abs(m - m.mean()).max())},
               "com": {"x": float(np.mean(self.com[ok, 0])), "y": float(np.mean(self.com[ok, 1]))},
               "effects": list(self.effects), "params": self.params,
               "wrench_residual": float(np.sqrt(np.mean(self.residual[ok] ** 2)))}
        if self.truth_mass:
            err = 100.0 * (m - self.truth_mass) / self.truth_mass
            out["truth"] = {"mass": self.truth_mass, "mass_error_percent": float(err.mean()),
                            "max_error_percent": float(np.abs(err).max())}
            if self.truth_com is not None:
                out["truth"]["com"] = {"x": float(self.truth_com[0]), "y": float(self.truth_com[1])}
        return out


def estimate_arrays(arr: CdprArrays, description, effects=(), params: dict | None = None) -> Estimate:
    """Mass and CoM per sample with the model ``baseline + effects`` (001 eq. 12-13).

    Nuisance parameters the model needs and ``params`` does not give (an unknown sheave radius,
    winch friction, sensor offsets) are identified first on the same data with the workbench
    (separable least squares); then the tensions are corrected and eq. 13 is applied per sample,
    vectorised.
    """
    from ...model import Model

    c = description.cdpr
    effs = tuple(baseline(description)) + tuple(e for e in effects if e not in baseline(description))
    Model("cdpr", effs)                                         # validates the ids
    params = dict(params or {})
    need = []
    if "pulley_geometry" in effs and "r_p" not in params:
        if c.pulley_radius > 0:
            params["r_p"] = c.pulley_radius
        else:
            need.append("r_p")
    fr = [e for e in effs if e in ("winch_coulomb_friction", "winch_viscous_friction", "tension_sensor_offset")]
    if need or fr:
        from ...fit import identify

        ds = dataset_from_arrays(arr, description)
        fixed = {"r_p": params["r_p"]} if "r_p" in params and "pulley_geometry" in effs else {}
        # W_I-based friction/offset columns: good to first order in r_p
        ident = identify(Model("cdpr", effs, fixed), ds)
        params.update({k: v for k, v in ident.params.items() if k not in ("m", "mx", "my", "m_a")})
    n = arr.tensions.shape[1]
    t = arr.tensions.copy()
    names = [f"winch_{i}" for i in range(1, n + 1)]
    if "winch_coulomb_friction" in effs or "winch_viscous_friction" in effs:
        fc = np.array([params.get(f"Fc[{w}]", 0.0) for w in names])
        fv = np.array([params.get(f"Fv[{w}]", 0.0) for w in names])
        s = np.sign(arr.motor_velocity)
        t = t - arr.scale * (fc * s + fv * arr.motor_velocity) if arr.source == "motor" else t
    if "tension_sensor_offset" in effs:
        t = t - np.array([params.get(f"b[{w}]", 0.0) for w in names])
    r = params.get("r_p", 0.0) if "pulley_geometry" in effs else 0.0
    check_pulley_radius(c.exit_points, c.anchor_points, arr.position, arr.R, r, c.swivel_axes,
                        "r_p (pulley_geometry)" if r != c.pulley_radius else "cdpr.pulley_radius")
    if arr.R is None and "platform_inertia" not in effs:      # level and static: fast kernel
        est = mass_com_batch(c.exit_points, c.anchor_points, arr.position, t, r,
                             description.gravity, c.swivel_axes)
    else:
        geom = cable_geometry(c.exit_points, c.anchor_points, arr.position, arr.R, r, c.swivel_axes)
        est = mass_com(geom, t, description.gravity,
                       arr.acc if "platform_inertia" in effs else None, arr.R)
    return Estimate(arr.t, est.mass, est.com, est.residual, effs,
                    {k: float(v) for k, v in params.items()}, arr.truth_mass, arr.truth_com)


def estimate_bag(bag_path, description=None, *, tensions: str = "dynamometer", effects=(),
                 pose: str = "desired", out=None, derived_velocity: dict | None = None) -> Estimate:
    """``cablelab estimate`` for a CDPR bag; ``out`` also writes ``/cdpr/payload_estimate``
    (InertiaStamped: m, com = (x_G, y_G, NaN), frame ``platform``) stamped like the tensions."""
    from ...bags import open_bag

    bag = bag_path if hasattr(bag_path, "joint_state") else open_bag(bag_path)   # path or open Bag
    desc = description if description is not None else bag.description
    if desc is None:
        raise CablelabError(f"{bag_path}: no /plant_description in the bag; give --description FILE")
    arr = load_arrays(bag, desc, tensions, pose, (derived_velocity or {}).get(JOINTS, ()))
    est = estimate_arrays(arr, desc, effects)
    if out is not None:
        from ...bags import BagWriter
        from ...description import dump_description

        with BagWriter(out, overwrite=True) as w:
            w.write_description(desc.yaml_text or dump_description(desc), float(est.t[0]))
            com = np.column_stack([est.com, np.full(len(est.t), np.nan)])
            w.write_inertia(ESTIMATE, est.t, est.mass, com)
    return est


def check_bag(bag, desc, options, series) -> list[str]:
    """Before a fit: one winch and one cable per described cable, no cable that pushes, tensions
    that are not all zero, and a geometry that can hold the platform (:func:`check_geometry`)."""
    from ...bagcheck import check_names, negative_tension_warnings

    warnings = []
    n = len(desc.cdpr.cables) if desc.cdpr is not None else None
    source = options.get("tensions") or "dynamometer"
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
        pose = series.get(REFERENCE) if (options.get("pose") or "desired") == "desired" else None
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


CDPR = register_plant(Plant(
    name="cdpr",
    topics=((JOINTS, JOINT_STATE),),
    dataset=dataset,
    baseline=baseline,
    candidates=candidates,
    remeasure=remeasure,
    channels_doc="cable wrench W t at the desired pose: Fx, Fy, Fz (N), Mx, My, Mz (N m) about "
                 "the platform origin, world axes",
    section=parse_section,
    dump_section=dump_section,
    contract_topics={
        JOINTS: JOINT_STATE,
        "/cdpr/cable_tensions": JOINT_STATE,
        "/cdpr/platform_pose": "geometry_msgs/msg/PoseStamped",
        "/cdpr/reference": "trajectory_msgs/msg/MultiDOFJointTrajectory",
        "/cdpr/effort_commands": "std_msgs/msg/Float64MultiArray",
        "/cdpr/payload_estimate": "geometry_msgs/msg/InertiaStamped",
        "/cdpr/ground_truth/pose": "geometry_msgs/msg/PoseStamped",
        "/cdpr/ground_truth/payload": "geometry_msgs/msg/InertiaStamped",
    },
    joint_topic=JOINTS,
    joints=tuple(f"winch_{i}" for i in range(1, 9)),
    capabilities=frozenset({"winch_actuators"}),
    estimate=estimate_bag,
    checked_topics=(TENSIONS, "/cdpr/reference", POSE),
    check_bag=check_bag,
    channels=CHANNELS,
    topic_names=lambda desc: _topic_names(desc),
    markers=lambda bag, desc: _bag_markers(bag, desc),
    options=("tensions", "pose"),
))


def _bag_markers(bag, desc):
    from .markers import bag_markers

    return bag_markers(bag, desc)


def _topic_names(desc) -> dict:
    """Element names of the CDPR JointState topics (CONTRACT sec. 2) for ``desc``'s cables."""
    n = len(desc.cdpr.cables) if desc is not None and desc.cdpr is not None else 8
    return {JOINTS: [f"winch_{i}" for i in range(1, n + 1)],
            TENSIONS: [f"cable_{i}" for i in range(1, n + 1)]}
