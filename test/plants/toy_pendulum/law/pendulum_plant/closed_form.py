"""Closed forms of the pendulum's law: the oracle the package's tests check the simulator against."""
from __future__ import annotations

import numpy as np

#: the constant-torque run of the test: torque (N m), duration (s), sample rate (Hz)
TORQUE, DURATION, RATE = 0.2, 20.0, 1000.0
G = 9.81   # m/s^2, the simulator's gravity


def constant_torque(section, run: dict) -> dict[str, tuple]:
    """The undamped pendulum from rest under :data:`TORQUE` swings about the angle where gravity
    balances the torque, ``m g l sin q* = tau``, with the small-oscillation period
    ``2 pi sqrt(l / (g cos q*))`` of the pendulum linearised there.

    Args:
        section: the description section; run: the simulator's run (``t``, ``q``).
    Returns:
        name -> (simulated, closed form, rtol, atol): the mean angle and the mean period between
        upward crossings of ``q*``.
    """
    q_eq = float(np.arcsin(TORQUE / (section.mass * G * section.length)))
    t, q = run["t"][1:], run["q"][1:]
    up = np.flatnonzero((q[:-1] < q_eq) & (q[1:] >= q_eq))
    period = float(np.mean(np.diff(t[up])))
    return {"mean angle": (float(q.mean()), q_eq, 0.02, 0.0),
            "period": (period, 2 * np.pi * np.sqrt(section.length / (G * np.cos(q_eq))), 0.02, 0.0)}
