"""The crane's excitation reference: smooth multi-sine joint trajectories (ROS-free and
MuJoCo-free, so the controller node evaluates it without loading the simulator)."""
from __future__ import annotations

import numpy as np

__all__ = ["reference_trajectory", "slew_only"]


def reference_trajectory(t, q0=(0.0, 0.5, 0.6), amplitude=(0.6, 0.25, 0.15), base_freq=0.08,
                         seed: int = 0):
    """Smooth multi-sine joint references for excitation (002 sec. 6.2 used sinusoidal commands).

    Returns ``(q_ref, qd_ref, qdd_ref)``, each (N, 3) [slew rad, luff rad, hoist m]; each joint is a
    sum of 3 sines with incommensurate frequencies starting at q0 with a smooth 2 s fade-in.
    """
    t = np.asarray(t, dtype=float)
    rng = np.random.default_rng(seed)
    qr, qdr, qddr = [], [], []
    ramp_t = 2.0
    s = np.clip(t / ramp_t, 0, 1)
    w = s ** 3 * (10 - 15 * s + 6 * s * s)                       # smoothstep fade-in
    wd = np.where(t < ramp_t, 30 * s * s * (1 - s) ** 2 / ramp_t, 0.0)
    wdd = np.where(t < ramp_t, 60 * s * (1 - s) * (1 - 2 * s) / ramp_t ** 2, 0.0)
    for j in range(3):
        f = base_freq * np.array([1.0, 1.618, 2.414]) * (1 + 0.3 * j) * rng.uniform(0.9, 1.1, 3)
        ph = rng.uniform(0, 2 * np.pi, 3)
        a = amplitude[j] / np.array([1.0, 1.8, 3.0])
        om = 2 * np.pi * f
        arg = om[None, :] * t[:, None] + ph[None, :]
        x = (a * (np.sin(arg) - np.sin(ph))).sum(1)
        xd = (a * om * np.cos(arg)).sum(1)
        xdd = (-a * om ** 2 * np.sin(arg)).sum(1)
        qr.append(q0[j] + w * x)
        qdr.append(wd * x + w * xd)
        qddr.append(wdd * x + 2 * wd * xd + w * xdd)
    return np.stack(qr, 1), np.stack(qdr, 1), np.stack(qddr, 1)


def slew_only(amplitude: float = 0.3, hz: float = 0.1, luff: float = 0.5, rope: float = 0.6):
    """A reference ``fn(t) -> (q, qd, qdd)`` (each (N, 3)) that only slews (a sine of ``amplitude``
    rad at ``hz``), luff (rad) and rope (m) held: a recording that leaves the hoist effort
    offset and the payload mass confounded (the experiment-design demo's and benchmark's first
    recording)."""
    w = 2 * np.pi * hz

    def fn(t):
        t = np.asarray(t, float)
        q, qd, qdd = (np.zeros((t.size, 3)) for _ in range(3))
        q[:, 0] = amplitude * np.sin(w * t)
        qd[:, 0] = amplitude * w * np.cos(w * t)
        qdd[:, 0] = -amplitude * w * w * np.sin(w * t)
        q[:, 1], q[:, 2] = luff, rope
        return q, qd, qdd

    return fn
