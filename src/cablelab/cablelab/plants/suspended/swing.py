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

IMU (spec 5.2, LiCAS BNO055 on the shoulder structure; axes = platform axes): when an IMU sample
(:meth:`SwingEstimator.imu`) is at most ``imu_max_lag`` s from a pose sample, the yaw comes from
the IMU orientation (carried to the pose stamp with the gyro's yaw rate) and the yaw rate from
the gyro, without the low-pass lag:
:func:`yaw_rate` is the exact derivative of ``atan2(R10, R00)`` for ``Rdot = [w]x R``
(world angular velocity ``w = R w_body``): ``w_z - R20 (w_x R00 + w_y R10) / (R00^2 + R10^2)``.
Without a recent IMU sample the pose is used again.
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np

__all__ = ["CHANNELS", "swing_angles", "yaw_from_quat", "yaw_rate", "swing_from_pose",
           "SwingEstimator", "SwingSample"]

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


def yaw_rate(R, omega_world) -> np.ndarray:
    """d/dt of ``atan2(R10, R00)`` (rad/s) for rotation matrices R (..., 3, 3) turning at world
    angular velocity ``omega_world`` (..., 3): exact (see module docstring)."""
    R = np.asarray(R, float)
    w = np.asarray(omega_world, float)
    r00, r10, r20 = R[..., 0, 0], R[..., 1, 0], R[..., 2, 0]
    return w[..., 2] - r20 * (w[..., 0] * r00 + w[..., 1] * r10) / (r00 ** 2 + r10 ** 2)


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
    source: str = "pose"        # of yaw and its rate: "pose" or "imu"


class SwingEstimator:
    """Live swing/yaw estimator (spec sec. 5.2).

    Args:
        S: (3,) suspension point, m. rest_pos: (3,) rest position or None (mean of the first
        ``rest_window`` s). rest_yaw: rad or None. velocity_tau: low-pass time constant, s.
        imu_max_lag: largest stamp difference, s, between a pose and the IMU sample used with it.
    """

    def __init__(self, S, *, rest_pos=None, rest_yaw=None, rest_window: float = 2.0,
                 velocity_tau: float = 0.05, imu_max_lag: float = 0.05):
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
        self.imu_max_lag = float(imu_max_lag)
        self._imu = None                   # (t, raw yaw, yaw rate) of the last good IMU sample
        self.held = 0                      # samples held (not estimated) ...
        self.last_problem = ""             # ... and why, the last time
        self.from_imu = 0                  # estimates whose yaw came from the IMU

    @classmethod
    def of_parameters(cls, v) -> "SwingEstimator":
        """The estimator node's estimator from its validated parameters ``v``
        (:data:`.nodes.parameters.ESTIMATOR`; a NaN rest position or yaw: from the rest window)."""
        rest = v.rest_position if all(np.isfinite(v.rest_position)) else None
        return cls(v.suspension_point, rest_window=v.rest_window, imu_max_lag=v.imu_max_lag, rest_pos=rest,
                   rest_yaw=v.rest_yaw if np.isfinite(v.rest_yaw) else None, velocity_tau=v.velocity_tau)

    def imu(self, t: float, quat_wxyz, gyro) -> bool:
        """Take one IMU sample: orientation (4,) w x y z (IMU = platform frame to world) and
        angular velocity (3,) rad/s in the IMU frame. False (ignored) if NaN, zero or of wrong
        length; the estimator then keeps using the pose once the last good sample is too old."""
        from ...rotations import quat_to_matrix

        q = np.asarray(quat_wxyz, float)
        w = np.asarray(gyro, float)
        if q.shape != (4,) or w.shape != (3,) or not (np.all(np.isfinite(q)) and np.all(np.isfinite(w))) \
                or not np.any(q):
            return False
        R = quat_to_matrix(q)
        self._imu = (float(t), float(yaw_from_quat(q)), float(yaw_rate(R, R @ w)))
        return True

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
        imu = self._imu if self._imu is not None and abs(t - self._imu[0]) <= self.imu_max_lag else None
        # (IMU yaw carried to the pose stamp with its own rate: exact for equal stamps)
        yaw_raw = imu[1] + imu[2] * (t - imu[0]) if imu is not None else float(yaw_from_quat(quat))
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
        if imu is not None:
            self._vel[2] = imu[2]          # gyro: no finite difference, no low-pass lag
        self._prev_t, self._prev_x = t, xk
        self.from_imu += imu is not None
        return SwingSample(xk, self._vel.copy(), True, source="pose" if imu is None else "imu")

    def _hold(self, msg: str) -> SwingSample:
        self.held += 1
        self.last_problem = msg
        x = self._prev_x if self._prev_x is not None else np.full(5, np.nan)
        return SwingSample(np.array(x), self._vel.copy(), False, msg)
