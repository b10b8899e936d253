"""Independent planar reference of the LiCAS virtual-joint model (spec 000_suspended.md sec. 4.5).

y-z plane reduction: q7 = q9 = q10 = q12 = 0, arms frozen at q = 0. Body A (links 8, 9 and the
J10 link, turning with th1 = q8 about S) and body B (J11 link + platform + arms, turning with
th2 = q8 + q11 about the lower attachment point at distance L). Lagrangian (000 eq. 1 in these
coordinates):

``T = 1/2 J_A th1d^2 + 1/2 M_B |v_B|^2 + 1/2 I_B th2d^2``,
``p_B = L [sin th1, -cos th1] + c_B [sin th2, -cos th2]``,
``V = -g [(m_A c_A + M_B L) cos th1 + M_B c_B cos th2]``.

Generalised forces: ``-f_v8 th1d`` on th1; levelling ``tendon`` (``U = k_p/2 th2^2``, damping
``k_d th2d``, acting on th2 only) or ``paper`` (torque ``tau = -k_p th2 - k_d th2d`` on q11
only, i.e. ``+tau`` on th2 and ``-tau`` on th1). Integrated with ``scipy.integrate.solve_ivp``.
The lumped inertias are computed here from the parameter set with the parallel-axis theorem,
independently of MuJoCo.
"""
from __future__ import annotations

import numpy as np
from scipy.integrate import solve_ivp

from .mjcf import effective_cable_inertias
from .params import VirtualParams

__all__ = ["planar_bodies", "planar_reference"]


def planar_bodies(p: VirtualParams) -> dict:
    """Lumped planar quantities (SI): J_A (kg m^2 about S), mcA (= m_A c_A, kg m), M_B (kg),
    c_B (CoM depth below the lower attachment point, m), I_B (about the CoM, kg m^2)."""
    (_, I8, I9), _ = effective_cable_inertias(p)
    J_A = I8[0] + p.m8 * p.l8z ** 2 + I9[0] + p.m9 * p.l9z ** 2 + p.I_plat[0] + p.m_plat * p.L ** 2
    mcA = p.m8 * p.l8z + p.m9 * p.l9z + p.m_plat * p.L
    # body B: link 11 + platform (CoM c_plat) + both arms at q = 0 (link frames aligned)
    masses, pts, ixx = [p.m_plat, p.m_plat], [np.array(p.c_plat)] * 2, [p.I_plat[0]] * 2
    for s in (1.0, -1.0):
        o = np.array(p.arm_mount) * [1, s, 1]
        for i, a in enumerate(p.arm):
            if i > 0:
                o = o + np.array(a.pos) * [1, s, 1]
            masses.append(a.mass)
            pts.append(o + np.array(a.com) * [1, s, 1])
            ixx.append(a.inertia[0])
    masses, pts = np.array(masses), np.array(pts)
    M = masses.sum()
    com = (masses[:, None] * pts).sum(0) / M
    I_B = float(np.sum(ixx) + np.sum(masses * ((pts[:, 1] - com[1]) ** 2 + (pts[:, 2] - com[2]) ** 2)))
    return {"J_A": float(J_A), "mcA": float(mcA), "M_B": float(M), "c_B": float(-com[2]),
            "y_B": float(com[1]), "I_B": I_B}


def planar_reference(p: VirtualParams, q8_0: float, q11_0: float, t_eval, *, levelling="tendon",
                     g: float = 9.81, rtol: float = 1e-10, atol: float = 1e-12) -> np.ndarray:
    """(N, 2) [q8, q11] of the planar reduction at times ``t_eval`` (s), from rest."""
    b = planar_bodies(p)
    JA, mcA, M, c, IB = b["J_A"], b["mcA"], b["M_B"], b["c_B"], b["I_B"]
    L, kp, kd, fv = p.L, p.kp11, p.kd11, p.fv[1]

    def rhs(_, x):
        th1, th2, w1, w2 = x
        s12, c12 = np.sin(th1 - th2), np.cos(th1 - th2)
        Mm = np.array([[JA + M * L * L, M * L * c * c12], [M * L * c * c12, M * c * c + IB]])
        h = np.array([M * L * c * s12 * w2 * w2, -M * L * c * s12 * w1 * w1])
        grav = np.array([g * (mcA + M * L) * np.sin(th1), g * M * c * np.sin(th2)])
        if levelling == "tendon":
            Q = np.array([-fv * w1, -kp * th2 - kd * w2])
        else:
            tau = -kp * th2 - kd * w2
            Q = np.array([-fv * w1 - tau, tau])
        acc = np.linalg.solve(Mm, Q - h - grav)
        return [w1, w2, acc[0], acc[1]]

    t_eval = np.asarray(t_eval, float)
    sol = solve_ivp(rhs, (0.0, float(t_eval[-1])), [q8_0, q8_0 + q11_0, 0.0, 0.0], t_eval=t_eval,
                    method="DOP853", rtol=rtol, atol=atol)
    th1, th2 = sol.y[0], sol.y[1]
    return np.stack([th1, th2 - th1], axis=1)
