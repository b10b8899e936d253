"""Platform swing and yaw from the measured platform pose (spec 000_suspended.md sec. 5.2).

With ``d = p - S`` and ``l = |d|``: ``swing_x = atan2(d_y, -d_z)`` (= q8 of 000) and
``swing_y = asin(-d_x / l)`` (= q9), the exact inverse of ``p = S + Rx(swing_x) Ry(swing_y)
[0, 0, -L]`` (``d = [-l sin q9, l cos q9 sin q8, -l cos q9 cos q8]``; 000 eq. 4 drops the
cos q9 factor and mislabels the axes, defect D7). ``r_x, r_y`` = platform position minus the
rest position (000 eq. 4 output x_s), ``yaw = atan2(R10, R00)`` unwrapped minus the rest yaw
(= q7 + q10 when level, 000 eq. 4 phi^z).

:func:`swing_from_pose` is the batch form (vectorised over time); :class:`SwingEstimator` is the
live one (``step`` per pose sample, finite-difference rates through a first-order low-pass
``velocity_tau``, NaN / frozen-stamp samples held and flagged).
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np

__all__ = ["CHANNELS", "swing_angles", "yaw_from_quat", "swing_from_pose", "SwingEstimator",
           "SwingSample"]

#: names of /suspended/swing_estimate (CONTRACT)
CHANNELS = ("swing_x", "swing_y", "yaw", "r_x", "r_y")


def swing_angles(pos, S) -> tuple[np.ndarray, np.ndarray]:
    """(swing_x, swing_y), rad, of platform positions ``pos`` (..., 3) hung from ``S`` (3,)."""
    d = np.asarray(pos, float) - np.asarray(S, float)
    l = np.linalg.norm(d, axis=-1)
    return np.arctan2(d[..., 1], -d[..., 2]), np.arcsin(np.clip(-d[..., 0] / l, -1.0, 1.0))


def yaw_from_quat(quat_wxyz) -> np.ndarray:
    """Raw yaw ``atan2(R10, R00)`` (rad, in (-pi, pi]) of unit quaternions (..., 4) w x y z."""
    q = np.asarray(quat_wxyz, float)
    w, x, y, z = q[..., 0], q[..., 1], q[..., 2], q[..., 3]
    return np.arctan2(2 * (x * y + w * z), 1 - 2 * (y * y + z * z))


def swing_from_pose(pos, quat_wxyz, S, *, rest_pos=None, rest_yaw=None, t=None,
                    rest_window: float = 2.0) -> dict:
    """Batch swing estimate: ``{name: (N,) array}`` for :data:`CHANNELS`.

    Args:
        pos: (N, 3) platform positions, m. quat_wxyz: (N, 4) platform orientations.
        S: (3,) suspension point, m.
        rest_pos, rest_yaw: rest pose; default = mean over the first ``rest_window`` s of ``t``
            (or the first sample when ``t`` is None).
    """
    pos = np.asarray(pos, float)
    sx, sy = swing_angles(pos, S)
    yaw = np.unwrap(yaw_from_quat(quat_wxyz))
    if t is None:
        k = 1
    else:
        t = np.asarray(t, float)
        k = max(1, int(np.searchsorted(t, t[0] + rest_window)))
    rp = np.asarray(rest_pos, float) if rest_pos is not None else pos[:k].mean(axis=0)
    ry = float(rest_yaw) if rest_yaw is not None else float(yaw[:k].mean())
    return {"swing_x": sx, "swing_y": sy, "yaw": yaw - ry, "r_x": pos[:, 0] - rp[0],
            "r_y": pos[:, 1] - rp[1]}


@dataclass
class SwingSample:
    """One live estimate: positions / rates of :data:`CHANNELS` and a health flag."""

    position: np.ndarray
    velocity: np.ndarray
    ok: bool
    message: str = ""


class SwingEstimator:
    """Live swing/yaw estimator (spec sec. 5.2).

    Args:
        S: (3,) suspension point, m. rest_pos: (3,) rest position or None (mean of the first
        ``rest_window`` s). rest_yaw: rad or None. velocity_tau: low-pass time constant, s.
    """

    def __init__(self, S, *, rest_pos=None, rest_yaw=None, rest_window: float = 2.0,
                 velocity_tau: float = 0.05):
        self.S = np.asarray(S, float)
        self.rest_pos = None if rest_pos is None else np.asarray(rest_pos, float)
        self.rest_yaw = rest_yaw
        self.rest_window = float(rest_window)
        self.tau = float(velocity_tau)
        self._t0 = None
        self._acc = []
        self._prev_t = None
        self._prev_x = None
        self._vel = np.zeros(5)
        self._yaw_prev = None
        self._yaw_unwrapped = 0.0

    def step(self, t: float, pos, quat_wxyz) -> SwingSample:
        """Process one pose sample (``t`` s, ``pos`` (3,) m, ``quat_wxyz`` (4,))."""
        pos = np.asarray(pos, float)
        quat = np.asarray(quat_wxyz, float)
        if pos.shape != (3,) or quat.shape != (4,) or not (np.all(np.isfinite(pos)) and np.all(np.isfinite(quat))):
            return self._hold("pose sample NaN or wrong length: held")
        if self._prev_t is not None and t <= self._prev_t:
            return self._hold(f"frozen stamp {t:.6f} s: held")
        d = pos - self.S
        l = float(np.sqrt(d @ d))
        sx = np.arctan2(d[1], -d[2])
        sy = np.arcsin(min(1.0, max(-1.0, -d[0] / l)))
        w, x, y, z = quat
        yaw_raw = np.arctan2(2 * (x * y + w * z), 1 - 2 * (y * y + z * z))
        if self._yaw_prev is None:
            self._yaw_unwrapped = yaw_raw
        else:
            self._yaw_unwrapped += (yaw_raw - self._yaw_prev + np.pi) % (2 * np.pi) - np.pi
        self._yaw_prev = yaw_raw
        if self._t0 is None:
            self._t0 = t
        if self.rest_pos is None or self.rest_yaw is None:
            if t - self._t0 < self.rest_window or not self._acc:
                self._acc.append(np.r_[pos, self._yaw_unwrapped])
            if t - self._t0 >= self.rest_window or self.rest_window <= 0:
                m = np.mean(self._acc, axis=0)
                if self.rest_pos is None:
                    self.rest_pos = m[:3]
                if self.rest_yaw is None:
                    self.rest_yaw = float(m[3])
        rp = self.rest_pos if self.rest_pos is not None else np.mean(self._acc, axis=0)[:3]
        ry = self.rest_yaw if self.rest_yaw is not None else float(np.mean(self._acc, axis=0)[3])
        xk = np.array([sx, sy, self._yaw_unwrapped - ry, pos[0] - rp[0], pos[1] - rp[1]])
        if self._prev_t is not None:
            dt = t - self._prev_t
            raw = (xk - self._prev_x) / dt
            a = dt / (self.tau + dt)
            self._vel = self._vel + a * (raw - self._vel)
        self._prev_t, self._prev_x = t, xk
        return SwingSample(xk, self._vel.copy(), True)

    def _hold(self, msg: str) -> SwingSample:
        x = self._prev_x if self._prev_x is not None else np.full(5, np.nan)
        return SwingSample(np.array(x), self._vel.copy(), False, msg)
