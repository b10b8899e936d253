"""Boom-crane kinematics and the exact swing-angle estimator (CONTRACT section 2, 002 sec. 6.3).

Frames: ``world`` is z-up with its origin at the luff pivot on the slew axis. The slewing frame
is ``world`` rotated by the slew angle alpha about z. With boom length l_b (m)::

    tip     = l_b [cos(beta) cos(alpha), cos(beta) sin(alpha), sin(beta)]
    payload = tip + Rz(alpha) d [sin(theta2), sin(theta1) cos(theta2), -cos(theta1) cos(theta2)]

(002 eq. A.3-A.4; theta1 tangential, theta2 radial). The exact inverse, with
``D' = Rz(alpha)^T (payload - tip)`` (002 eq. 6.4) and ``d = |D'|`` (002 eq. 6.5), is
``theta2 = asin(D'x / d)``, ``theta1 = atan2(D'y, -D'z)``; 002 eq. 6.6-6.7 are its small-angle
approximations and 002 eq. 5.2-5.3 (no rotation) are what the absolute frame gets wrong.

Everything is vectorised over time: angles (N,), positions (N, 3), SI units (m, rad, s).
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np

__all__ = [
    "boom_tip", "rope_direction", "payload_position", "slewing_offset", "swing_from_offset",
    "swing_from_positions", "swing_rates_from_offset", "absolute_frame_swing_002",
    "SwingAngles", "gimbal_to_swing", "gimbal_rates_to_swing", "swing_to_gimbal",
]


def _cs(x):
    x = np.asarray(x, dtype=float)
    return np.cos(x), np.sin(x)


def boom_tip(alpha, beta, boom_length: float) -> np.ndarray:
    """(N, 3) boom-tip pivot in ``world`` (CONTRACT sec. 2), m."""
    ca, sa = _cs(alpha)
    cb, sb = _cs(beta)
    ca, sa, cb, sb = np.broadcast_arrays(ca, sa, cb, sb)
    return boom_length * np.stack([cb * ca, cb * sa, sb], axis=-1)


def rope_direction(theta1, theta2) -> np.ndarray:
    """(N, 3) unit vector from tip to payload in the slewing frame (002 eq. A.3-A.4)."""
    c1, s1 = _cs(theta1)
    c2, s2 = _cs(theta2)
    c1, s1, c2, s2 = np.broadcast_arrays(c1, s1, c2, s2)
    return np.stack([s2, s1 * c2, -c1 * c2], axis=-1)


def _rotate_z(vec: np.ndarray, alpha, inverse: bool = False) -> np.ndarray:
    ca, sa = _cs(alpha)
    if inverse:
        sa = -sa
    x, y = vec[..., 0], vec[..., 1]
    return np.stack([ca * x - sa * y, sa * x + ca * y, np.broadcast_to(vec[..., 2], np.broadcast(x, ca).shape)],
                    axis=-1)


def payload_position(alpha, beta, d, theta1, theta2, boom_length: float) -> np.ndarray:
    """(N, 3) payload pivot in ``world``: tip + Rz(alpha) d u(theta1, theta2), m."""
    u = rope_direction(theta1, theta2) * np.asarray(d, dtype=float)[..., None]
    return boom_tip(alpha, beta, boom_length) + _rotate_z(u, alpha)


def slewing_offset(tip, payload, alpha) -> np.ndarray:
    """(N, 3) D' = Rz(alpha)^T (payload - tip): tip-to-payload vector in the slewing frame (002 eq. 6.4)."""
    delta = np.asarray(payload, dtype=float) - np.asarray(tip, dtype=float)
    return _rotate_z(delta, alpha, inverse=True)


def swing_from_offset(offset: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Exact inverse of the swing parameterisation: ``(theta1, theta2, d)`` from D' (N, 3).

    theta2 = asin(D'x / d), theta1 = atan2(D'y, -D'z), d = |D'| (CONTRACT sec. 2). NaN rows stay NaN.
    """
    x, y, z = offset[..., 0], offset[..., 1], offset[..., 2]
    d = np.sqrt(x * x + y * y + z * z)
    with np.errstate(invalid="ignore", divide="ignore"):
        theta2 = np.arcsin(np.clip(x / d, -1.0, 1.0))
    theta1 = np.arctan2(y, -z)
    return theta1, theta2, d


def swing_rates_from_offset(offset: np.ndarray, offset_rate: np.ndarray):
    """``(theta1_dot, theta2_dot, d_dot)`` from D' and its time derivative in the slewing frame.

    Derivatives of :func:`swing_from_offset`: d_dot = D'.D'_dot / d,
    theta2_dot = (x_dot d - x d_dot) / (d^2 cos theta2), theta1_dot = (y z_dot - y_dot z) / (y^2 + z^2).
    """
    x, y, z = offset[..., 0], offset[..., 1], offset[..., 2]
    xd, yd, zd = offset_rate[..., 0], offset_rate[..., 1], offset_rate[..., 2]
    d = np.sqrt(x * x + y * y + z * z)
    with np.errstate(invalid="ignore", divide="ignore"):
        d_dot = (x * xd + y * yd + z * zd) / d
        r = y * y + z * z  # = d^2 cos^2 theta2
        theta2_dot = (xd * d - x * d_dot) / np.sqrt(r) / d
        theta1_dot = (y * zd - yd * z) / r
    return theta1_dot, theta2_dot, d_dot


def absolute_frame_swing_002(tip, payload) -> tuple[np.ndarray, np.ndarray]:
    """The *wrong* swing angles of 002 eq. 5.2-5.3 / 6.1-6.2 (absolute frame, no Rz(alpha)).

    Kept only to show, in tests and reports, what 002 sec. 6.3 found: theta1 and theta2 swap
    when the slew angle changes by 90 degrees.
    """
    delta = np.asarray(payload, dtype=float) - np.asarray(tip, dtype=float)
    dx, dy, dz = delta[..., 0], delta[..., 1], delta[..., 2]
    theta1 = -np.arcsin(np.clip(dy / np.sqrt(dx * dx + dz * dz), -1, 1))
    theta2 = np.arcsin(np.clip(dx / np.sqrt(dy * dy + dz * dz), -1, 1))
    return theta1, theta2


@dataclass(frozen=True)
class SwingAngles:
    """Swing estimate over N samples (SI units): the ``/crane/swing_estimate`` content.

    Attributes:
        t: (N,) sample times, s.
        theta1, theta2: (N,) tangential / radial swing angles, rad.
        rope_length: (N,) d, m.
        theta1_dot, theta2_dot, rope_length_dot: (N,) velocities, rad/s and m/s.
        valid: (N,) False where the sample was reconstructed (dropout) or is unusable.
    """

    t: np.ndarray
    theta1: np.ndarray
    theta2: np.ndarray
    rope_length: np.ndarray
    theta1_dot: np.ndarray
    theta2_dot: np.ndarray
    rope_length_dot: np.ndarray
    valid: np.ndarray

    @property
    def position(self) -> np.ndarray:
        """(N, 3) [theta1, theta2, rope_length]."""
        return np.stack([self.theta1, self.theta2, self.rope_length], axis=1)

    @property
    def velocity(self) -> np.ndarray:
        """(N, 3) [theta1_dot, theta2_dot, rope_length_dot]."""
        return np.stack([self.theta1_dot, self.theta2_dot, self.rope_length_dot], axis=1)


def swing_from_positions(tip, payload, alpha) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """``(theta1, theta2, d)`` from mocap positions of tip and payload (N, 3) and slew angle (N,)."""
    return swing_from_offset(slewing_offset(tip, payload, alpha))


# ----------------------------------------------------------------------------- simulator coordinates
# The MuJoCo tree (cablelab.plants.crane.sim) hangs the payload from the boom tip by two hinges fixed in the
# boom: psi about the luff axis (-y) then phi about the rotated x, then the hoist slide d along -z.
# Because the luff axis is the slewing-frame y axis, the rope direction in the slewing frame is
# R_{-y}(beta + psi) R_x(phi) [0, 0, -1] = [sin(gam) cos(phi), sin(phi), -cos(gam) cos(phi)],
# gam = beta + psi. These helpers map that gimbal to the swing angles of CONTRACT sec. 2.

def gimbal_to_swing(beta, psi, phi) -> tuple[np.ndarray, np.ndarray]:
    """``(theta1, theta2)`` of the rope direction given by the simulator gimbal (rad)."""
    gam = np.asarray(beta, dtype=float) + np.asarray(psi, dtype=float)
    cphi, sphi = _cs(phi)
    theta2 = np.arcsin(np.clip(np.sin(gam) * cphi, -1.0, 1.0))
    theta1 = np.arctan2(sphi, np.cos(gam) * cphi)
    return theta1, theta2


def gimbal_rates_to_swing(beta, psi, phi, beta_dot, psi_dot, phi_dot):
    """``(theta1_dot, theta2_dot)`` from the gimbal angles and rates (chain rule of gimbal_to_swing)."""
    gam = np.asarray(beta, dtype=float) + np.asarray(psi, dtype=float)
    gam_dot = np.asarray(beta_dot, dtype=float) + np.asarray(psi_dot, dtype=float)
    cg, sg = np.cos(gam), np.sin(gam)
    cphi, sphi = _cs(phi)
    x, y = cg * cphi, sphi                       # tan(theta1) = y / x
    xd = -sg * cphi * gam_dot - cg * sphi * phi_dot
    yd = cphi * phi_dot
    theta1_dot = (x * yd - y * xd) / (x * x + y * y)
    s2 = sg * cphi                               # sin(theta2)
    s2d = cg * cphi * gam_dot - sg * sphi * phi_dot
    theta2_dot = s2d / np.sqrt(1.0 - s2 * s2)
    return theta1_dot, theta2_dot


def swing_to_gimbal(beta, theta1, theta2) -> tuple[np.ndarray, np.ndarray]:
    """``(psi, phi)`` of the simulator gimbal giving swing angles theta1, theta2 at luff angle beta."""
    u = rope_direction(theta1, theta2)
    phi = np.arcsin(np.clip(u[..., 1], -1.0, 1.0))
    gam = np.arctan2(u[..., 0], -u[..., 2])
    return gam - np.asarray(beta, dtype=float), phi
