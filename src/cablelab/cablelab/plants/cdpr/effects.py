"""CDPR effects (CONTRACT section 4) on the wrench-balance channels of the CDPR dataset.

The CDPR dataset (:mod:`cablelab.plants.cdpr`) measures the cable wrench y = W(x) t (6 channels:
forces N, moments N m about the platform origin, world axes) from the measured tensions t and the
wrench matrix W at the desired (or measured) pose. The model explains it as (001 eq. 10-13)

    W t = [m g_up; (m x_G R e_x + m y_G R e_y) x g_up]      (cdpr_gravity: m, mx, my)
          + [m_a a; R [mx_a, my_a, mz_a] x a]                (platform_inertia)
          + W (R/r) (F_c sign(qdot) + F_v qdot)             (winch friction, motor tensions only)
          + W b                                             (tension_sensor_offset, dynamometers)

The friction and offset terms act on the cables, so they reach the wrench through the model's
wrench matrix: W_II(r_p) = W_I + r_p S (below) with pulleys. Their columns use the described sheave
radius (:func:`cablelab.plants.cdpr.dataset.model_wrench_matrix`, exact when the model's r_p is the described one); when r_p is
fitted (pulleys not described) the second-order term (r_p - r_desc) S b is left out.

With ``--tensions both`` (dynamometers and motor torques in the bag) the dataset adds one
torque-balance channel per winch, ``(R/r) tau_i - d_i`` (N; tau_i the motor torque, d_i the
dynamometer reading), modelled as (001 eq. 15 minus the dynamometer reading t_i + b_i)

    (R/r) tau_i - d_i = (R/r) (F_c,i sign(qdot_i) + F_v,i qdot_i) - b_i

while winch i moves (zeroed in its zero-speed zone); the wrench channels then come from the
dynamometers and carry no friction. The weight, inertia and sheave terms are 0 on these channels.

``pulley_geometry`` is the switch from Model I (point exits, the dataset's W) to Model II (001
eq. 6-9). The measured channels stay W_I t (so every candidate is scored on the same data) and the
pulleys enter as W_I t = w_model - r_p S t, S = (W_II(r_ref) - W_I) / r_ref the secant slope of
the wrench matrix in the sheave radius (r_ref = the description's r_p, else 0.15 m): linear in
r_p, exact at r_ref. ``cablelab estimate`` then uses the exact Model II with the fitted r_p.
"""
from __future__ import annotations

import numpy as np

from ...dataset import Dataset
from ...effects.base import Effect, Param
from ...rotations import cross
from ...effects import register
from ...effects.base import Physical
from ...effects.friction import coulomb_regressor, stribeck_effect, viscous_regressor

#: search range of the sheave radius r_p, m
PULLEY_BOUNDS = (0.0, 0.4)


def _wrench_only(ds: Dataset, blk: np.ndarray) -> np.ndarray:
    """A (N, 6, p) wrench-channel block padded with zeros for the torque-balance channels of a
    ``--tensions both`` dataset (the weight, inertia and sheaves do not enter the balance)."""
    extra = ds.n_channels - blk.shape[1]
    if extra <= 0:
        return blk
    return np.concatenate([blk, np.zeros((blk.shape[0], extra, blk.shape[2]))], axis=1)


def _platform_axes(ds: Dataset) -> np.ndarray:
    """(N, 3, 3) the platform's axes (columns) in world axes per sample (level: the world's)."""
    R = ds.signals.get("R")
    return np.broadcast_to(np.eye(3), (ds.n, 3, 3)) if R is None else R


def _gravity(ds: Dataset) -> np.ndarray:
    up = np.zeros((ds.n, 3))
    up[:, 2] = ds.gravity
    R = _platform_axes(ds)
    out = np.zeros((ds.n, 6, 3))
    out[:, :3, 0] = up
    out[:, 3:, 1] = cross(R[:, :, 0], up)
    out[:, 3:, 2] = cross(R[:, :, 1], up)
    return _wrench_only(ds, out)


def _inertia(ds: Dataset) -> np.ndarray:
    # 001 eq. 10's spatial inertia times the acceleration of a translating platform:
    # [m_a a; MS_a x a], MS_a = R [mx_a, my_a, mz_a] its first moment (001 eq. 11's MS_p; no
    # angular acceleration, no gyroscopic term: the platform keeps its orientation). Unlike the
    # weight's, the moment of m a also sees the height of the centre of mass (mz_a).
    a = ds.require_signal("acc")
    R = _platform_axes(ds)
    out = np.zeros((ds.n, 6, 4))
    out[:, :3, 0] = a
    for k in range(3):
        out[:, 3:, 1 + k] = cross(R[:, :, k], a)
    return _wrench_only(ds, out)


def _pulley(ds: Dataset) -> np.ndarray:
    # W_I t = w_model - r_p S t with S = (W(r_ref) - W(0)) / r_ref (the dataset's "pulley_slope"):
    # exact at r_p = r_ref, second order in (r_p - r_ref) elsewhere
    return _wrench_only(ds, -ds.require_signal("pulley_slope")[:, :, None])


def _tension_offset(ds: Dataset) -> np.ndarray:
    # wrench channels: W b; torque-balance channels ((R/r) tau_i - d_i, --tensions both): -b_i
    # while winch i moves (the channel is zeroed at rest, see plants.cdpr.dataset.balance_mask)
    from .dataset import model_wrench_matrix

    W = model_wrench_matrix(ds.require_signal("W"), ds.require_signal("pulley_S"), ds.description)
    mask = ds.signals.get("balance_mask")
    if mask is None:
        return W
    n = mask.shape[1]
    bal = np.zeros((ds.n, n, n))
    idx = np.arange(n)
    bal[:, idx, idx] = -mask
    return np.concatenate([W, bal], axis=1)


CDPR_GRAVITY = register(Effect(
    id="cdpr_gravity",
    plants=("cdpr",),
    params=(Param("m", "kg", 366.0, 0.0, np.inf, "total moving mass (platform + payload)"),
            Param("mx", "kg m", 0.0, -np.inf, np.inf, "first moment m x_G (platform frame)"),
            Param("my", "kg m", 0.0, -np.inf, np.inf, "first moment m y_G (platform frame)")),
    explanation="the cables carry the weight of the platform and payload at its centre of mass",
    signature="the whole static wrench",
    reference="001 eq. 11-13",
    regressor=_gravity,
    physical=lambda ds: (
        Physical("m", "kg", lambda p: p["m"], "total moving mass (001 eq. 11)"),
        Physical("x_G", "m", lambda p: p["mx"] / p["m"], "centre of mass x, platform frame (001 eq. 13)"),
        Physical("y_G", "m", lambda p: p["my"] / p["m"], "centre of mass y, platform frame (001 eq. 13)")),
))

PLATFORM_INERTIA = register(Effect(
    id="platform_inertia",
    plants=("cdpr",),
    params=(Param("m_a", "kg", 366.0, 0.0, np.inf, "mass accelerated with the platform"),
            Param("mx_a", "kg m", 0.0, -np.inf, np.inf, "its first moment m_a x_G (platform frame)"),
            Param("my_a", "kg m", 0.0, -np.inf, np.inf, "its first moment m_a y_G (platform frame)"),
            Param("mz_a", "kg m", 0.0, -np.inf, np.inf, "its first moment m_a z_G (platform frame)")),
    explanation="the cables also accelerate the moving mass (m a in the force balance, m r_G x a "
                "in the moment balance)",
    signature="mass estimate swings with the vertical acceleration (lift and lower phases)",
    reference="001 eq. 10",
    regressor=_inertia,
    physical=lambda ds: (
        Physical("m_a", "kg", lambda p: p["m_a"], "mass accelerated with the platform (001 eq. 10)"),
        Physical("x_Ga", "m", lambda p: p["mx_a"] / p["m_a"], "its centre of mass x, platform frame"),
        Physical("y_Ga", "m", lambda p: p["my_a"] / p["m_a"], "its centre of mass y, platform frame"),
        Physical("z_Ga", "m", lambda p: p["mz_a"] / p["m_a"], "its centre of mass z, platform frame")),
))

PULLEY_GEOMETRY = register(Effect(
    id="pulley_geometry",
    plants=("cdpr",),
    params=(Param("r_p", "m", 0.15, PULLEY_BOUNDS[0], PULLEY_BOUNDS[1], "sheave radius"),),
    explanation="cables leave the swivel pulleys at the moving tangent point of a sheave of "
                "radius r_p, not at a fixed point (Model II)",
    signature="mass underestimated by a pose-dependent factor; horizontal force imbalance",
    reference="001 eq. 6-9, Table I",
    regressor=_pulley,
))

WINCH_COULOMB_FRICTION = register(Effect(
    id="winch_coulomb_friction",
    plants=("cdpr",),
    params=(Param("Fc", "{effort}", 0.0, 0.0, np.inf, "Coulomb friction of the winch, motor side"),),
    explanation="a constant motor torque is lost to dry friction, changing sign with the winch",
    signature="mass estimate from motor torques jumps when winches reverse",
    reference="001 eq. 15, Table II",
    regressor=coulomb_regressor("winch_coulomb_friction"),
    per_actuator=True,
))

WINCH_VISCOUS_FRICTION = register(Effect(
    id="winch_viscous_friction",
    plants=("cdpr",),
    params=(Param("Fv", "{effort} s/{position}", 0.0, 0.0, np.inf, "viscous friction of the winch"),),
    explanation="motor torque lost in proportion to the winch speed",
    signature="mass estimate from motor torques drifts with the cable speeds",
    reference="001 eq. 15",
    regressor=viscous_regressor("winch_viscous_friction"),
    per_actuator=True,
))

TENSION_SENSOR_OFFSET = register(Effect(
    id="tension_sensor_offset",
    plants=("cdpr",),
    params=(Param("b", "N", 0.0, -np.inf, np.inf, "constant bias of the dynamometer"),),
    explanation="a dynamometer reads its cable tension plus a constant bias",
    signature="wrench residual constant in the platform frame, also at rest",
    reference="001 sec. II-B (dynamometer calibration)",
    regressor=_tension_offset,
    per_actuator=True,
))

WINCH_STRIBECK_FRICTION = register(stribeck_effect("winch_stribeck_friction", ("cdpr",),
                                             "CONTRACT sec. 4; 001 eq. 15 with a Stribeck term"))
