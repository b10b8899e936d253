"""PD on motor angles with real-time mass feedforward (PDFF, 001 sec. IV, Fig. 6, eq. 14-15).

tau = K_p (q_d - q) + K_d (qdot_d - qdot) + r/R t_ff + F_c sign(qdot_d) + F_v qdot_d

with q_d from the inverse geometric model (motor angle = -(R/r) * cable length, so a positive
motor angle reels the cable in, CONTRACT section 2), qdot_d = (R/r) W^T [v_d; w_d] (001 eq. 5,
J = -W^T), t_ff the tensions of 001 eq. 14 (W^+ m (a_d + g), here the solution nearest a uniform
preload so the distribution stays positive) and a minimum-tension floor. PD = the same law with
``mass = None`` (no feedforward: 001's "PD" whose initial torque is zero).
All functions accept a leading batch axis (samples) and hold no state.
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from ...rotations import cross
from .estimation import winch_friction
from .geometry import CableGeometry, wrench_matrix

__all__ = ["PdffConfig", "motor_angles", "motor_rates", "feedforward_tensions", "pdff_torques",
           "cable_lengths_from_motor"]


@dataclass(frozen=True)
class PdffConfig:
    """Controller parameters (motor side, SI).

    Args:
        kp: proportional gain, N m/rad (same for every motor, 001 sec. IV).
        kd: derivative gain, N m s/rad.
        coulomb, viscous: friction compensation F_c (N m), F_v (N m s/rad) of 001 eq. 15.
        min_tension: floor on the commanded tension so cables stay taut, N.
        preload: uniform tension the feedforward distribution stays nearest to, N.
        max_torque: saturation of the motor torque, N m.
        pulley_radius: r_p of the model used in the IGM and W (None = the description's).
    """

    kp: float = 0.6
    kd: float = 0.04
    coulomb: float = 0.0
    viscous: float = 0.0
    min_tension: float = 50.0
    preload: float = 300.0
    max_torque: float = 40.0
    pulley_radius: float | None = None


def motor_angles(lengths: np.ndarray, drum_radius: float, gear_ratio: float) -> np.ndarray:
    """Inverse geometric model in motor angles: q = -(R/r) l (rad; zero = zero paid-out length)."""
    return -(gear_ratio / drum_radius) * np.asarray(lengths, dtype=float)


def cable_lengths_from_motor(q: np.ndarray, drum_radius: float, gear_ratio: float) -> np.ndarray:
    """Paid-out cable lengths (m) from motor angles, inverse of :func:`motor_angles`."""
    return -(drum_radius / gear_ratio) * np.asarray(q, dtype=float)


def motor_rates(geom: CableGeometry, velocity: np.ndarray, drum_radius: float, gear_ratio: float,
                angular_velocity: np.ndarray | None = None) -> np.ndarray:
    """Desired motor rates qdot = (R/r) W^T [v; w] (001 eq. 5), rad/s, shape (N, n)."""
    v = np.atleast_2d(np.asarray(velocity, dtype=float))
    ldot = -np.einsum("tni,ti->tn", geom.directions, v)
    if angular_velocity is not None:
        w = np.atleast_2d(np.asarray(angular_velocity, dtype=float))
        ldot = ldot - np.einsum("tni,tni->tn", geom.directions, cross(w[:, None, :], geom.anchors))
    return -(gear_ratio / drum_radius) * ldot


def feedforward_tensions(geom: CableGeometry, mass, acceleration: np.ndarray, gravity: float = 9.81,
                         com: np.ndarray | None = None, preload: float = 300.0,
                         min_tension: float = 0.0, pinv: np.ndarray | None = None) -> np.ndarray:
    """Tensions of 001 eq. 14: t = W^+ w with w = [m (a + g); m c x (a + g)] (c = CoM offset in
    world axes; None = eq. 14 exactly, no moment), taken nearest a uniform preload
    (t = t_p + W^+ (w - W t_p), which only adds a null-space internal force) and floored.

    Args:
        geom: cable geometry at the desired poses (N samples).
        mass: total moving mass, kg (scalar or (N,)).
        acceleration: (N, 3) desired acceleration, m/s^2.
        com: optional (N, 3) or (3,) centre of mass from the platform origin, world axes, m.
        pinv: optional precomputed (N, n, 6) W^+.
    """
    W = wrench_matrix(geom)
    a = np.atleast_2d(np.asarray(acceleration, dtype=float))
    f = a + np.array([0.0, 0.0, gravity])
    m = np.asarray(mass, dtype=float).reshape(-1, 1)
    w = np.zeros((W.shape[0], 6))
    w[:, :3] = m * f
    if com is not None:
        w[:, 3:] = m * cross(np.broadcast_to(com, f.shape), f)
    n = W.shape[2]
    tp = np.full(n, float(preload))
    rhs = w - W @ tp
    if pinv is None:   # W^+ rhs = W^T (W W^T)^-1 rhs for a full-row-rank W (6 x n, n >= 6)
        y = np.linalg.solve(W @ W.transpose(0, 2, 1), rhs[..., None])[..., 0]
        t = tp + np.einsum("tji,tj->ti", W, y)
    else:
        t = tp + np.einsum("tij,tj->ti", pinv, rhs)
    return np.maximum(t, min_tension)


def pdff_torques(q: np.ndarray, qdot: np.ndarray, q_des: np.ndarray, qdot_des: np.ndarray,
                 tensions_ff: np.ndarray | None, drum_radius: float, gear_ratio: float,
                 config: PdffConfig) -> np.ndarray:
    """Motor torque commands (N m) of 001 Fig. 6 with eq. 14 (``tensions_ff``; None = PD) and
    eq. 15 friction compensation on the desired rates; floored at r/R * min_tension plus the
    friction compensation, saturated at max_torque."""
    k = drum_radius / gear_ratio
    tau = config.kp * (np.asarray(q_des) - q) + config.kd * (np.asarray(qdot_des) - qdot)
    if tensions_ff is not None:
        tau += k * np.asarray(tensions_ff)
    tau = np.maximum(tau, k * config.min_tension)
    tau += winch_friction(qdot_des, config.coulomb, config.viscous)
    return np.minimum(np.maximum(tau, -config.max_torque), config.max_torque, out=tau)
