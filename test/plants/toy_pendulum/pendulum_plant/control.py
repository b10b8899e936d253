"""Control laws of the plant (ROS-free, vectorised over time): the excitation the simulator and
the controller node drive the hinge with."""
from __future__ import annotations

import numpy as np


def chirp(t, duration: float, amplitude: float = 0.3, f0: float = 0.2, f1: float = 2.0):
    """Torque (N m) of a linear chirp from ``f0`` to ``f1`` Hz over ``duration`` s at time(s) ``t``."""
    t = np.asarray(t, dtype=float)
    rate = (f1 - f0) / max(duration, 1e-9)
    return amplitude * np.sin(2 * np.pi * (f0 * t + 0.5 * rate * t * t))
