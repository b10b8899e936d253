"""Bag -> :class:`cablelab.dataset.Dataset` for the workbench on ``suspended`` runs.

The workbench model is linear in its parameters (:mod:`cablelab.model`), so the platform
motion is written as the swing equations of 000 eq. 1 reduced to one generalised coordinate per
mode (cable angles q8 = swing_x, q9 = swing_y about S, and platform yaw phi^z):

``J_x qdd8 = -[mgl_x sin q8 + f_v8 qd8 + f_s8 sign(qd8) + ...]`` (channel ``swing_x``, N m),
the same for ``swing_y`` (q9) and ``J_z phidd = -[k_yaw phi + f_v7 phid + ...]`` (``yaw``).

Channel ``stretch`` (N): the radial equation of the lower body (mass M_r, everything below the
rope) on a cable of measured length ``l = |p - S|``, with ``d`` = l minus its median (the dynamic
stretch about the static one) and ``u`` the cable direction (``|udot|^2 = qd9^2 + cos^2 q9 qd8^2``):
``M_r (ddd - l |udot|^2) - M_r g (cos q8 cos q9 - 1) = -[k_c d + c_c dd]``. A rigid cable keeps
d at zero (the channel is then not excited and zeroed); an elastic one bounces (spec sec. 7
``cable_elasticity``).

Output y = nominal inertia x measured angular acceleration, with the nominal modal inertias of
the description's parameter set (:func:`modal_inertias`: the links turning with each joint plus
the platform and arms translating at distance L, spec 4.5). The swing angles come from the
platform pose (:mod:`.swing`), conditioned by :func:`cablelab.conditioning.condition_motion`
(uniform grid, zero-phase Butterworth, central differences). The effects of
:mod:`.effects` supply the bracketed terms as regressor columns.
"""
from __future__ import annotations

import dataclasses

import numpy as np

from ...conditioning import condition_motion
from ...errors import CablelabError
from ...dataset import Dataset
from ...plant_interface import DatasetOptions
from . import topics
from .params import VirtualParams
from .reference import planar_bodies
from .swing import swing_from_pose

__all__ = ["dataset", "dataset_from_arrays", "modal_inertias", "radial_mass", "platform_tilt", "CHANNELS",
           "POSE_TOPIC", "SUSPENSION_TOPIC", "JOINT_STATES", "CUTOFF_HZ", "rest_mask"]

CHANNELS = ("swing_x", "swing_y", "yaw", "stretch")
POSE_TOPIC = topics.PLATFORM_POSE
SUSPENSION_TOPIC = topics.SUSPENSION_POSE
JOINT_STATES = topics.JOINT_STATES
POSE = topics.POSE
#: position low-pass cut-off, Hz: the swing is at 0.5 Hz (LiCAS) / 0.24 Hz (CRANEbot), yaw below
#: 0.6 Hz; 1 mm of mocap noise differentiated twice needs a low cut-off (cf. crane: 3 Hz)
CUTOFF_HZ = 2.0
#: amplitude below which a channel counts as not excited: swing_x, swing_y, yaw (rad), stretch (m;
#: 1 mm of mocap noise low-passed at 2 Hz stays well below 3 mm)
MIN_AMPLITUDE = (0.01, 0.01, 0.02, 0.003)
#: rest: every excited mode slower than this share of its 99th-percentile speed for a whole swing
#: period (cf. :data:`cablelab.velocity.ZONE_FRACTION`: a swing's turning point is far shorter)
REST_FRACTION = 0.03


def rest_mask(t: np.ndarray, qd: np.ndarray, excited: np.ndarray, period: float,
              fraction: float = REST_FRACTION) -> np.ndarray:
    """(N,) True where the platform is at rest: every excited swing/yaw mode (``qd`` (N, 3),
    ``excited`` (3,)) stays inside its zero-speed zone (``fraction`` x its p99 speed) over a
    window of one swing ``period`` (s) around the sample. A swing that dry friction stops holds
    still at a finite angle: there the friction is whatever balances gravity (stiction), not
    ``f_s sign(qd)``, and the sign of a filtered noise velocity is noise, so no candidate can
    predict those samples and they carry no dynamics; a turning point of a moving swing lasts a
    small part of a period and is never a rest."""
    qd = np.abs(np.asarray(qd, float)[:, :3])[:, np.asarray(excited[:3], bool)]
    n = len(t)
    if qd.shape[1] == 0 or n < 3:
        return np.zeros(n, bool)
    zone = fraction * np.nanpercentile(qd, 99, axis=0)
    slow = np.all(qd < zone, axis=1).astype(float)
    w = max(int(round(period / max(float(np.median(np.diff(t))), 1e-9))), 1)
    # a sample is at rest when a whole window containing it is slow
    full = np.convolve(slow, np.ones(w), "valid") >= w - 0.5           # windows [i, i + w)
    rest = np.zeros(n, bool)
    starts = np.flatnonzero(full)
    if starts.size:
        cover = np.zeros(n + 1)
        np.add.at(cover, starts, 1.0)
        np.add.at(cover, starts + w, -1.0)
        rest = np.cumsum(cover)[:n] > 0
    return rest


def modal_inertias(p: VirtualParams) -> np.ndarray:
    """(3,) nominal inertias of the modes q8, q9, phi^z, kg m^2.

    q8: links 8, 9, 10 about S plus the lower body (platform + arms, mass M_B) translating at L
    (the levelled platform does not rotate). q9: link 9, 10 and the lower body. Yaw: the lower
    body's inertia about the vertical through the attachment point (arms at q = 0).
    """
    b = planar_bodies(p)
    from .mjcf import effective_cable_inertias
    (_, I8, I9), _ = effective_cable_inertias(p)
    Jx = b["J_A"] + b["M_B"] * p.L ** 2
    Jy = I9[1] + p.m9 * p.l9z ** 2 + p.I_plat[1] + p.m_plat * p.L ** 2 + b["M_B"] * p.L ** 2
    # yaw: platform links + arm links about z through the attachment point
    Jz = 2 * p.I_plat[2]
    for s in (1.0, -1.0):
        o = np.array(p.arm_mount) * [1, s, 1]
        for i, a in enumerate(p.arm):
            if i > 0:
                o = o + np.array(a.pos) * [1, s, 1]
            c = o + np.array(a.com) * [1, s, 1]
            Jz += a.inertia[2] + a.mass * (c[0] ** 2 + c[1] ** 2)
    return np.array([Jx, Jy, Jz])


def platform_tilt(quat_wxyz) -> np.ndarray:
    """(N, 2) world tilt of the platform about x and y, rad: the body z axis
    ``z_b = Rx(a) Ry(b) e_z = (sin b, -sin a cos b, cos a cos b)`` (independent of yaw), so
    ``a = atan2(-z_b,y, z_b,z)``, ``b = asin(z_b,x)``; for the chain J8..J12 (000 eq. 1) a = q8 + q11
    and b = q9 + q12 to first order."""
    w, x, y, z = np.asarray(quat_wxyz, float).T
    zb = np.stack([2 * (x * z + w * y), 2 * (y * z - w * x), 1 - 2 * (x * x + y * y)], -1)
    return np.column_stack([np.arctan2(-zb[:, 1], zb[:, 2]), np.arcsin(np.clip(zb[:, 0], -1.0, 1.0))])


def dataset_from_arrays(t, pos, quat_wxyz, desc_section, description=None, options: DatasetOptions | None = None,
                        *, source: str = "data", suspension=None) -> Dataset:
    """Dataset from platform poses ``pos`` (N, 3) m and ``quat_wxyz`` (N, 4) at stamps ``t`` (N,).

    ``suspension``: measured position of the suspension point S at the same stamps (N, 3) m, or
    None (S fixed at the description's ``S``). When given, the swing angles are taken about the
    moving S and its acceleration is the signal ``a_S`` of ``suspension_motion``."""
    opts = (options or DatasetOptions()).conditioning
    if opts.cutoff_hz is None:
        opts = dataclasses.replace(opts, cutoff_hz=CUTOFF_HZ)
    p = desc_section.params()
    S = np.broadcast_to(np.asarray(p.S, float), np.shape(pos)) if suspension is None else np.asarray(suspension, float)
    s = swing_from_pose(pos, quat_wxyz, S, rest_pos=np.array(p.S) - [0, 0, p.L], rest_yaw=0.0)
    l = np.linalg.norm(np.asarray(pos, float) - S, axis=1)
    q = np.column_stack([s["swing_x"], s["swing_y"], s["yaw"], l - np.median(l)])
    # conditioned together with the swing (same grid and filter): platform tilt, S
    extra = np.column_stack([platform_tilt(quat_wxyz), S])
    c = condition_motion(np.asarray(t, float), np.column_stack([q, extra]), np.zeros((len(q), 1)), opts,
                         revolute=False, source=source)
    tilt, tilt_d = c["q"][:, 4:6], c["qd"][:, 4:6]
    a_S = c["qdd"][:, 6:9]
    q, qd, qdd = c["q"][:, :4], c["qd"][:, :4], c["qdd"][:, :4]
    J = modal_inertias(p)
    g = description.gravity if description is not None else 9.81
    M_r = radial_mass(p)
    amp = np.abs(q[:, :2]).max(axis=1)
    edges = np.quantile(amp, [1 / 3, 2 / 3])
    labels = np.array(["small swing", "medium swing", "large swing"])
    y = np.empty_like(q)
    y[:, :3] = qdd[:, :3] * J
    lk = np.median(l) + q[:, 3]
    udot2 = qd[:, 1] ** 2 + np.cos(q[:, 1]) ** 2 * qd[:, 0] ** 2
    y[:, 3] = M_r * (qdd[:, 3] - lk * udot2) - M_r * g * (np.cos(q[:, 0]) * np.cos(q[:, 1]) - 1.0)
    # a channel the record does not excite carries only differentiated noise: its output is
    # zeroed (the columns keep the measured motion, so every parameter stays fitted, to ~0)
    excited = np.abs(q - q.mean(axis=0)).max(axis=0) > MIN_AMPLITUDE
    y[:, ~excited] = 0.0
    period = 2 * np.pi * np.sqrt(p.L / g)
    rest = rest_mask(c["t"], qd, excited, period)
    ds = Dataset(
        plant="suspended", t=c["t"], y=y, channels=CHANNELS, units=("N m", "N m", "N m", "N"),
        signals={"q": q, "qd": qd, "qdd": qdd, "J": J, "g": g, "L": p.L, "excited": excited,
                 "cutoff_hz": c.get("cutoff_hz", opts.cutoff_hz), "tilt": tilt, "tilt_d": tilt_d,
                 "level_to_swing": bool(p.level_to_swing),
                 "a_S": a_S if suspension is not None else None},
        actuators=CHANNELS, act_vel=qd, act_units=(("N m", "rad"),) * 3 + (("N", "m"),),
        inputs={"swing_x rate": qd[:, 0], "swing_y rate": qd[:, 1], "yaw rate": qd[:, 2]},
        regimes={"swing amplitude": labels[np.searchsorted(edges, amp)]},
        description=description, source=source)
    return _without_rests(ds, rest)


def _without_rests(ds: Dataset, rest: np.ndarray) -> Dataset:
    """The record cut to its moving span (a platform that dry friction stopped stays stopped:
    the tail would make whole cross-validation folds of stiction and noise) and the rests inside
    it marked not valid (not fitted, not scored, the same for every candidate); the share left
    out is kept as the signal ``rest_share``. A moving span shorter than the samples a diagnosis
    needs (:data:`cablelab.datachecks.MIN_SAMPLES`) keeps the first rest samples after it, valid,
    up to that count."""
    from ...datachecks import MIN_SAMPLES

    moving = np.flatnonzero(~rest)
    if not rest.any() or moving.size == 0:
        return ds.replace(signals={**ds.signals, "rest_share": 0.0})
    first, last = int(moving[0]), int(moving[-1]) + 1
    end = min(max(last, first + MIN_SAMPLES), ds.n)
    span = np.arange(first, end)
    out = ds.subset(span)
    inside = rest[span] & (span < last)
    return out.replace(valid=out.valid & ~inside,
                       signals={**out.signals, "rest_share": 1.0 - float(np.sum(out.valid & ~inside)) / ds.n})


def radial_mass(p: VirtualParams) -> float:
    """Mass below the rope (link 10 and the lower body: platform links + arms), kg: what an
    axial cable spring carries (the slide joint of :func:`.mjcf.virtual_xml` sits in link 10)."""
    return float(planar_bodies(p)["M_B"] + p.m_plat)


def section_of(description):
    """The parsed ``suspended:`` section of a description (one-line error without it)."""
    sec = getattr(description, "suspended", None)
    if sec is None:
        raise CablelabError("description: plant suspended needs a 'suspended:' section")
    return sec


def dataset(bag, description, options: DatasetOptions) -> Dataset:
    """Workbench dataset of a ``suspended`` bag (``/suspended/platform_pose``)."""
    bag.require(POSE_TOPIC, POSE)
    ps = bag.pose(POSE_TOPIC)
    quat = ps.quaternion[:, [3, 0, 1, 2]]                 # x y z w -> w x y z
    S = None
    if bag.has(SUSPENSION_TOPIC):                          # optional measured input
        bag.require(SUSPENSION_TOPIC, POSE)
        ss = bag.pose(SUSPENSION_TOPIC)
        if len(ss.t) < 2:
            raise CablelabError(f"{bag.path}: topic {SUSPENSION_TOPIC} has {len(ss.t)} message(s), needs >= 2")
        S = np.column_stack([np.interp(ps.t, ss.t, ss.position[:, k]) for k in range(3)])
    return dataset_from_arrays(ps.t, ps.position, quat, section_of(description), description,
                               options, source=str(bag.path), suspension=S)
