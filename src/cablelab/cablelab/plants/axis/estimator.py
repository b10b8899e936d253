"""The axis live parameter estimator (ROS-free): recursive least squares of the inverse model
``u - m c g sin q = M qdd + Fv qd + Fc sign(qd) + offset`` (:func:`.control.regressor`) from
consecutive joint-state samples, one sample at a time (the ``payload_estimator --plant axis``
node feeds it)."""
from __future__ import annotations

import math

from .control import gravity_load, regressor
from ...rls import RecursiveLeastSquares

__all__ = ["AxisRlsEstimator", "NAMES"]

#: the estimated parameters, in order
NAMES = ("M", "Fv", "Fc", "offset")


class AxisRlsEstimator:
    """``step(t, q, qd, effort)`` per sample; :attr:`theta` is ``[M, Fv, Fc, offset]``.

    qdd and the mid-interval velocity come from two consecutive samples, the force from the later
    one (a simulator reports with each sample the command held over the period ending there); a
    velocity that is not measured (NaN) is the position difference over the interval. A sample
    not later than the previous one is ignored.

    Args:
        forgetting: forgetting factor lambda (1 = none).
        stiction_velocity: |qd| below which sign(qd) counts as 0 (m/s or rad/s).
    """

    def __init__(self, forgetting: float = 1.0, stiction_velocity: float = 1e-3):
        self.rls = RecursiveLeastSquares(4, lam=forgetting, p0=1e4)
        self.eps = stiction_velocity
        self.gravity_moment, self.gravity = 0.0, 9.81
        self.prev: tuple | None = None      # (t, q, qd, effort)

    @property
    def theta(self):
        return self.rls.theta

    def set_gravity(self, gravity_moment: float, gravity: float) -> None:
        """A revolute axis's gravity load ``m c`` (kg m) and g (m/s^2), subtracted from the force."""
        self.gravity_moment, self.gravity = gravity_moment, gravity

    def step(self, t: float, q: float, qd: float, effort: float) -> bool:
        """Take one sample (``qd`` NaN: not measured); True when it updated the estimate."""
        cur = (t, q, qd, effort)
        prev, self.prev = self.prev, cur
        if prev is None or not t > prev[0]:
            return False
        dt = t - prev[0]
        v0 = prev[2] if math.isfinite(prev[2]) else (q - prev[1]) / dt
        v1 = qd if math.isfinite(qd) else (q - prev[1]) / dt
        y = effort - gravity_load(0.5 * (prev[1] + q), self.gravity_moment, self.gravity)
        self.rls.update(regressor([0.5 * (v0 + v1)], [(v1 - v0) / dt], self.eps), [y])
        return True
