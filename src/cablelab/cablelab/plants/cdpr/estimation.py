"""Payload mass and centre of mass from cable tensions (001 sec. III-D, eq. 12-13), and cable
tensions from motor torques with friction compensation (001 eq. 15, CONTRACT section 2).

All functions are vectorised over time (leading axis N = samples) and free of ROS.
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from ...effects.friction import coulomb_sign
from ...rotations import cross
from .geometry import CableGeometry, cable_wrench

__all__ = ["MassCom", "mass_com", "mass_com_batch", "mass_com_from_wrench", "tensions_from_torques",
           "torques_from_tensions", "winch_friction"]


@dataclass(frozen=True)
class MassCom:
    """Per-sample estimate of the moving mass and its centre of mass.

    Attributes:
        mass: (N,) total moving mass m (platform + payload), kg.
        com: (N, 2) centre of mass (x_G, y_G) in the platform frame, m.
        residual: (N,) wrench-balance residual: norm of the part of W t the rigid-body model
            m (g + a), m c x (g + a) cannot explain (horizontal force and yaw moment), N.
    """

    mass: np.ndarray
    com: np.ndarray
    residual: np.ndarray


def mass_com_from_wrench(wrench: np.ndarray, gravity: float = 9.81,
                         acceleration: np.ndarray | None = None,
                         rotation: np.ndarray | None = None, com_z: float = 0.0) -> MassCom:
    """Mass and CoM from the cable wrench W t (001 eq. 13, with the m*a term of eq. 10 optional).

    With the specific force f = a - g_vec (f = [0, 0, g] at rest), the balance is
    W t = [m f; m c x f] with c the CoM in world axes from the platform origin. The mass is the
    least-squares fit of the force part along f (at rest: m = (W t)_z / g, 001 eq. 13) and
    (c_x, c_y) the least-squares fit of the moment part for the given c_z (at rest and level:
    y_G = (W t)_4 / (m g), x_G = -(W t)_5 / (m g), 001 eq. 13).

    Args:
        wrench: (N, 6) cable wrench W t (forces N, moments N m about the platform origin).
        gravity: g, m/s^2.
        acceleration: (N, 3) platform acceleration (desired or measured), m/s^2; None = static
            (001 assumption 2). Adding it is the ``platform_inertia`` effect (001 eq. 10).
        rotation: (N, 3, 3) platform rotation used to express the CoM in the platform frame;
            None = level platform (001 assumption 1).
        com_z: z of the CoM in the platform frame, m (unobservable when static; assumed).
    """
    w = np.atleast_2d(np.asarray(wrench, dtype=float))
    F, M = w[:, :3], w[:, 3:]
    if acceleration is None and rotation is None:
        # static, level platform: 001 eq. 13 as printed (z_G drops out, its moment is zero)
        m = F[:, 2] / gravity
        mg = F[:, 2]
        com = np.empty((len(m), 2))
        with np.errstate(divide="ignore", invalid="ignore"):    # no load: CoM undefined (NaN/inf)
            com[:, 0] = -M[:, 1] / mg
            com[:, 1] = M[:, 0] / mg
        res = np.sqrt(F[:, 0] ** 2 + F[:, 1] ** 2 + M[:, 2] ** 2)
        return MassCom(m, com, res)
    f = np.zeros_like(F)
    f[:, 2] = gravity
    if acceleration is not None:
        f = f + np.atleast_2d(np.asarray(acceleration, dtype=float))
    ff = np.einsum("ti,ti->t", f, f)
    m = np.einsum("ti,ti->t", F, f) / ff
    if rotation is None:
        Rm = np.broadcast_to(np.eye(3), (len(m), 3, 3))
    else:
        Rm = np.broadcast_to(np.asarray(rotation, dtype=float), (len(m), 3, 3))
    # moment = m (c_w x f), c_w = x_G R e_x + y_G R e_y + z_G R e_z: linear in (x_G, y_G)
    Mr = M / np.where(np.abs(m) > 1e-9, m, np.nan)[:, None] - com_z * cross(Rm[:, :, 2], f)
    a1 = cross(Rm[:, :, 0], f)
    a2 = cross(Rm[:, :, 1], f)
    a11 = np.einsum("ti,ti->t", a1, a1)
    a22 = np.einsum("ti,ti->t", a2, a2)
    a12 = np.einsum("ti,ti->t", a1, a2)
    r1 = np.einsum("ti,ti->t", a1, Mr)
    r2 = np.einsum("ti,ti->t", a2, Mr)
    det = a11 * a22 - a12 * a12
    xg = (a22 * r1 - a12 * r2) / det
    yg = (a11 * r2 - a12 * r1) / det
    c = np.stack([xg, yg], -1)
    model_M = m[:, None] * (xg[:, None] * a1 + yg[:, None] * a2 + com_z * cross(Rm[:, :, 2], f))
    res = np.sqrt(np.sum((F - m[:, None] * f) ** 2, 1) + np.sum((M - model_M) ** 2, 1))
    return MassCom(m, c, res)


def mass_com(geom: CableGeometry, tensions: np.ndarray, gravity: float = 9.81,
             acceleration: np.ndarray | None = None, rotation: np.ndarray | None = None,
             com_z: float = 0.0) -> MassCom:
    """Mass and CoM (x_G, y_G) from cable tensions and the wrench matrix of Model I or II
    (001 eq. 12-13); see :func:`mass_com_from_wrench` for the arguments.

    Args:
        geom: cable geometry at the (desired or measured) poses, from
            :func:`~cablelab.plants.cdpr.geometry.cable_geometry`.
        tensions: (N, n) cable tensions, N.
    """
    return mass_com_from_wrench(cable_wrench(geom, tensions), gravity, acceleration, rotation, com_z)


def winch_friction(velocity: np.ndarray, coulomb, viscous, deadband: float = 0.0) -> np.ndarray:
    """Motor-side friction torque F_c sign(qdot) + F_v qdot of 001 eq. 15, N m.

    Args:
        velocity: (N, n) motor velocities qdot, rad/s (positive reels in).
        coulomb: F_c per motor (scalar or (n,)), N m.
        viscous: F_v per motor (scalar or (n,)), N m s/rad.
        deadband: |qdot| below which sign() is taken as 0, rad/s.
    """
    v = np.asarray(velocity, dtype=float)
    return np.asarray(coulomb, float) * coulomb_sign(v, deadband) + np.asarray(viscous, float) * v


def tensions_from_torques(effort: np.ndarray, velocity: np.ndarray, drum_radius: float,
                          gear_ratio: float, coulomb=0.0, viscous=0.0,
                          deadband: float = 0.0) -> np.ndarray:
    """Cable tensions from measured motor torques (CONTRACT: effort = r/R t + friction):
    t = R / r (tau - F_c sign(qdot) - F_v qdot), 001 eq. 14-15 read backwards.

    Args:
        effort: (N, n) motor torques from current, N m (positive reels in).
        velocity: (N, n) motor velocities, rad/s.
        drum_radius: r, m.  gear_ratio: R (motor turns per drum turn).
        coulomb, viscous: friction parameters (0 = raw torques).
    """
    tau = np.asarray(effort, dtype=float) - winch_friction(velocity, coulomb, viscous, deadband)
    return tau * (gear_ratio / drum_radius)


def torques_from_tensions(tensions: np.ndarray, velocity: np.ndarray, drum_radius: float,
                          gear_ratio: float, coulomb=0.0, viscous=0.0,
                          deadband: float = 0.0) -> np.ndarray:
    """Motor torques that hold the given tensions, r/R t + friction (001 eq. 14-15), N m."""
    return (np.asarray(tensions, dtype=float) * (drum_radius / gear_ratio)
            + winch_friction(velocity, coulomb, viscous, deadband))


def mass_com_batch(exit_points: np.ndarray, anchor_points: np.ndarray, position: np.ndarray,
                   tensions: np.ndarray, pulley_radius: float = 0.0, gravity: float = 9.81,
                   swivel_axes: np.ndarray | None = None, chunk: int = 4096) -> MassCom:
    """Fast offline Model I / II estimate (001 eq. 6-9, 12-13) for a level platform, over a long
    record: the same result as ``mass_com(cable_geometry(...), tensions)`` without rotation,
    computed per coordinate on (chunk, n) arrays that stay in cache (no (N, n, 3) temporaries).

    Args:
        exit_points (n, 3), anchor_points (n, 3): A_i (world), B_i (platform frame), m.
        position: (N, 3) platform positions, m.  tensions: (N, n), N.
        pulley_radius: r_p, m (0 = Model I).  swivel_axes: (n, 3), default +z.
    """
    A = np.asarray(exit_points, float)
    b = np.asarray(anchor_points, float)
    P = np.asarray(position, float)
    T = np.asarray(tensions, float)
    N, n = T.shape
    z = np.tile([0.0, 0.0, 1.0], (n, 1)) if swivel_axes is None else np.asarray(swivel_axes, float)
    r = float(pulley_radius)
    BA = b - A                                           # B_i - A_i at P = 0
    mass = np.empty(N)
    com = np.empty((N, 2))
    res = np.empty(N)
    bx, by, bz = b[:, 0], b[:, 1], b[:, 2]
    zx, zy, zz = z[:, 0], z[:, 1], z[:, 2]
    for s in range(0, N, chunk):
        p = P[s:s + chunk]
        t = T[s:s + chunk]
        dx = p[:, :1] + BA[:, 0]
        dy = p[:, 1:2] + BA[:, 1]
        dzw = p[:, 2:3] + BA[:, 2]
        if r > 0.0:
            dz = dx * zx + dy * zy + dzw * zz            # along the swivel axis
            hx, hy, hz = dx - dz * zx, dy - dz * zy, dzw - dz * zz
            h = np.sqrt(hx * hx + hy * hy + hz * hz)
            vx = h - r
            D2 = vx * vx + dz * dz
            lc = np.sqrt(D2 - r * r)
            cx = (r * vx - lc * dz) / D2
            cz = (r * dz + lc * vx) / D2
            a = r * (1.0 + cx) / h                       # A' - B = -d + a h_vec + r cz z
            c = r * cz
            w = t / lc
            fx = w * (a * hx + c * zx - dx)
            fy = w * (a * hy + c * zy - dy)
            fz = w * (a * hz + c * zz - dzw)
        else:
            w = t / np.sqrt(dx * dx + dy * dy + dzw * dzw)
            fx, fy, fz = -w * dx, -w * dy, -w * dzw
        Fx, Fy, Fz = fx.sum(1), fy.sum(1), fz.sum(1)
        Mx = (by * fz - bz * fy).sum(1)
        My = (bz * fx - bx * fz).sum(1)
        Mz = (bx * fy - by * fx).sum(1)
        sl = slice(s, s + len(t))
        mass[sl] = Fz / gravity
        com[sl, 0] = -My / Fz
        com[sl, 1] = Mx / Fz
        res[sl] = np.sqrt(Fx * Fx + Fy * Fy + Mz * Mz)
    return MassCom(mass, com, res)
