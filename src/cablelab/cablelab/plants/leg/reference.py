"""Independent reference simulation of the hybrid leg: plain scipy ``solve_ivp`` per phase with
terminal events (spec 003 sec. 4 "Independent reference"). Used by the tests as the oracle of the
MuJoCo plant (:mod:`.sim`); it shares nothing with it but the model laws of :mod:`.hybrid`, and it
writes the stance / flight right-hand sides out itself (003 eq. 1 and 23).

rtol 1e-10, atol 1e-12, max_step 1 ms; the velocity map (eq. 24) is applied between segments,
the E1 frozen-length rule included. The eq. 26 torque is the continuous law
``T sin(2 pi (t - t_d) / P)`` or, with ``zoh_dt``, held over each sample period like the 1 kHz
hardware loop (samples on the grid ``n * zoh_dt``).
"""
from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
from scipy.integrate import solve_ivp

from .hybrid import LegParams


@dataclass
class ReferenceResult:
    """Dense solution: ``sol(t) -> (z, zd)``; events ``(t, kind, z, zd_minus, zd_plus)``."""

    segments: list  # (t0, t1, phase, OdeSolution)
    events: list
    t_end: float

    def sample(self, t: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """(z, zd, phase) at times ``t`` (phase 1 = stance)."""
        t = np.asarray(t, float)
        z, zd, ph = np.full(t.shape, np.nan), np.full(t.shape, np.nan), np.zeros(t.shape, int)
        for t0, t1, phase, sol in self.segments:
            sel = (t >= t0 - 1e-9) & (t <= t1 + 1e-9)
            if sel.any():
                y = sol(t[sel])
                z[sel], zd[sel], ph[sel] = y[0], y[1], phase
        return z, zd, ph

    def apexes(self) -> list[tuple[float, float]]:
        """(t, z) of every flight apex (zd = 0 event in flight)."""
        return [(e[0], e[2]) for e in self.events if e[1] == "apex"]


def schedule_lookup(schedule, block_s: float, T: float, P: float):
    """``(T, P)`` of eq. 26 for a stance that starts at ``t_d``: the fixed pair, or the pair of
    the ``block_s``-long block of ``schedule`` that holds ``t_d`` (the last one after its end)."""
    if not schedule:
        return lambda t_d: (T, P)
    sched = [tuple(map(float, x)) for x in schedule]
    return lambda t_d: sched[min(int(max(t_d, 0.0) // block_s), len(sched) - 1)]


def run_reference(p: LegParams, z0: float, zd0: float, duration: float, T: float = 0.0,
                  P: float = 0.3, zoh_dt: float | None = None, *, schedule=None,
                  block_s: float = 4.0) -> ReferenceResult:
    """Simulate the hybrid leg from (z0, zd0) for ``duration`` s under 003 eq. 26 (T, P), or
    with ``schedule`` [(T, P), ...] a new pair every ``block_s`` s (chosen at each touch-down)."""
    pair = schedule_lookup(schedule, block_s, T, P)
    m, k, g = p.m, p.k, p.g
    mf = p.m if p.m_f is None else p.m_f
    z_td = 2.0 * p.L * math.cos(p.theta0)
    zr = z_td if p.z0 is None else p.z0

    def spring(z):
        e = zr - z
        return k * e * (1.0 + p.k2 * e + p.k3 * e * e) + p.F0

    def f_in(t, z, t_d):
        """eq. 26 torque through eq. 3 (continuous, or held over the sample period)."""
        if zoh_dt:
            t = math.floor(t / zoh_dt + 1e-9) * zoh_dt
            if t < t_d - 1e-12:  # the sample period of the touch-down carries no torque yet
                return 0.0
        Tn, Pn = pair(t_d)
        return Tn * math.sin(2.0 * math.pi * (t - t_d) / Pn) / math.sqrt(max(4.0 * p.L**2 - z * z, 1e-12))

    segments, events = [], []
    t, z, zd = 0.0, z0, zd0
    phase = 1 if z0 < z_td else 0
    l_fl, t_d = z_td, 0.0
    opts = dict(rtol=1e-10, atol=1e-12, max_step=1e-3, dense_output=True)
    while t < duration - 1e-12:
        if phase == 1:
            td = t_d

            def rhs(tt, y):
                fi = f_in(tt, y[0], td)
                # stance inertia m, weight m_f g (the link rotation adds inertia, not weight)
                return [y[1], (fi + spring(y[0]) - p.d_s * y[1] - p.Fc * np.sign(y[1]) - mf * g) / m]

            def lo_grf(tt, y):
                return f_in(tt, y[0], td) + spring(y[0]) - p.d_s * y[1]

            def lo_len(tt, y):
                return z_td - y[0]

            lo_grf.terminal = lo_len.terminal = True
            lo_grf.direction = lo_len.direction = -1
            # the lift-off guard is not armed at the touch-down instant (z = z_td there): the
            # event direction -1 ignores the upward crossing of z_td - z as the body descends
            sol = solve_ivp(rhs, (t, duration), [z, zd], events=[lo_grf, lo_len], **opts)
            t1, (z1, zd1) = sol.t[-1], sol.y[:, -1]
            segments.append((t, t1, 1, sol.sol))
            if sol.status == 1:
                zp = p.beta_lo * zd1
                events.append((t1, "liftoff", z1, zd1, zp))
                l_fl = min(z_td, z1)
                phase, zd1 = 0, zp
        else:
            def rhs(tt, y):
                return [y[1], -(p.d_f * y[1] + p.Fc * np.sign(y[1])) / mf - g]

            def td_ev(tt, y):
                return y[0] - l_fl

            def apex(tt, y):
                return y[1]

            td_ev.terminal, td_ev.direction = True, -1
            apex.terminal, apex.direction = False, -1
            sol = solve_ivp(rhs, (t, duration), [z, zd], events=[td_ev, apex], **opts)
            t1, (z1, zd1) = sol.t[-1], sol.y[:, -1]
            segments.append((t, t1, 0, sol.sol))
            for ta, ya in zip(sol.t_events[1], sol.y_events[1]):
                if ta > t + 1e-9:
                    events.append((float(ta), "apex", float(ya[0]), 0.0, 0.0))
            if sol.status == 1:
                zp = p.beta_td * zd1
                events.append((t1, "touchdown", z1, zd1, zp))
                phase, zd1, t_d = 1, zp, t1
        t, z, zd = float(t1), float(z1), float(zd1)
        if sol.status == 0:
            break
    events.sort(key=lambda e: e[0])
    return ReferenceResult(segments, events, t)


def sampled_trajectory(p: LegParams, z0: float, zd0: float, duration: float, T: float = 0.0,
                       P: float = 0.3, dt: float = 1e-3, *, resolution: float = 9e-5,
                       seed: int | None = 0, rtol: float | None = None, schedule=None,
                       block_s: float = 4.0, contact_delay: float = 0.0):
    """The reference solution sampled at ``dt`` like the hardware (continuous eq. 26 torque,
    sampled; 0.09 mm encoder, differentiated velocity, contact switch ``contact_delay`` s late) as
    a :class:`~cablelab.plants.leg.sim.Trajectory`: data for tests that the MuJoCo code did not
    generate. ``schedule``, ``block_s``: as :func:`run_reference`."""
    from .sim import Event, Trajectory, measure

    ref = run_reference(p, z0, zd0, duration, T, P, schedule=schedule, block_s=block_s)
    pair = schedule_lookup(schedule, block_s, T, P)
    t = np.arange(0.0, ref.t_end + 1e-12, dt)
    z, zd, ph = ref.sample(t)
    td = np.array([e[0] for e in ref.events if e[1] == "touchdown"])
    k = np.searchsorted(td, t, side="right") - 1
    t_d = np.where(k >= 0, td[np.maximum(k, 0)], 0.0)
    # the eq. 26 pair of each sample's stance (before the first touch-down: the pair at t = 0)
    TP = np.array([pair(0.0)] + [pair(x) for x in td])
    Tn, Pn = TP[k + 1, 0], TP[k + 1, 1]
    tau = np.where(ph == 1, Tn * np.sin(2 * np.pi * (t - t_d) / Pn), 0.0)
    f_in = np.where(ph == 1, tau / np.sqrt(np.maximum(4 * p.L**2 - z * z, 1e-12)), 0.0)
    g = np.where(ph == 1, f_in + p.k * (p.spring_rest - z) + p.F0 - p.d_s * zd, 0.0)
    events = [Event(float(e[0]), e[1], float(e[2]), float(e[3]), float(e[4]))
              for e in ref.events if e[1] != "apex"]
    traj = Trajectory(t, z, zd, ph, tau, f_in, g, events)
    return measure(traj, resolution=resolution, contact_delay=contact_delay, seed=seed)
