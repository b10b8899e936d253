"""The pick-and-place test trajectory of 001 sec. II-C (Fig. 2-3): A -> E in 30 s and back.

The paper gives the shape (lift from the pick point, travel across the workspace, lower onto the
place point, and back) and the timing (vertical phases at t = 0-5, 25-35 and 55-60 s, nearly
constant velocity in between) but not the coordinates, so the waypoints are parameters. Every
segment follows an s-curve (quintic time law 10 s^3 - 15 s^4 + 6 s^5, continuous velocity and
acceleration, zero at the waypoints; 001 ref. [14]); the platform stays level (001 assumption 1).
"""
from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

__all__ = ["Trajectory", "scurve", "pick_and_place", "CAROCA_WAYPOINTS", "sample_trajectory", "ReferenceTable"]

#: waypoints A..E of the test trajectory in the CAROCA world frame (m), platform origin.
CAROCA_WAYPOINTS = np.array([
    [-1.0, -0.3, 0.6],    # A: pick point
    [-1.0, -0.3, 1.1],    # B: lifted
    [0.0, 0.0, 1.1],      # C: mid-way
    [1.0, 0.3, 1.1],      # D: above the place point
    [1.0, 0.3, 0.6],      # E: place point
])


@dataclass(frozen=True)
class Trajectory:
    """A sampled platform reference: time (N,) s, position/velocity/acceleration (N, 3) in
    m, m/s, m/s^2, orientation (N, 4) unit quaternions (w, x, y, z)."""

    t: np.ndarray
    position: np.ndarray
    velocity: np.ndarray
    acceleration: np.ndarray
    orientation: np.ndarray = field(default=None)

    def __post_init__(self):
        if self.orientation is None:
            q = np.zeros((len(self.t), 4))
            q[:, 0] = 1.0
            object.__setattr__(self, "orientation", q)


def scurve(s: np.ndarray):
    """Quintic s-curve on s in [0, 1]: (position, d/ds, d2/ds2), all zero-velocity and
    zero-acceleration at both ends."""
    s = np.clip(s, 0.0, 1.0)
    p = s ** 3 * (10 - 15 * s + 6 * s * s)
    dp = 30 * s * s * (1 - s) ** 2
    ddp = 60 * s * (1 - s) * (1 - 2 * s)
    return p, dp, ddp


def _piecewise(t, knots_t, knots_x):
    """Positions, velocities, accelerations of s-curve segments between successive knots."""
    t = np.asarray(t, dtype=float)
    k = np.clip(np.searchsorted(knots_t, t, side="right") - 1, 0, len(knots_t) - 2)
    T = knots_t[k + 1] - knots_t[k]
    s = (t - knots_t[k]) / T
    p, dp, ddp = scurve(s)
    dx = knots_x[k + 1] - knots_x[k]
    x = knots_x[k] + p[:, None] * dx
    v = (dp / T)[:, None] * dx
    a = (ddp / T ** 2)[:, None] * dx
    return x, v, a


def pick_and_place(t: np.ndarray, waypoints: np.ndarray = CAROCA_WAYPOINTS,
                   lift_time: float = 5.0, travel_time: float = 20.0, hold: float = 0.0,
                   offset: np.ndarray | None = None) -> Trajectory:
    """Reference of 001 sec. II-C sampled at times t (s): A->B lift (lift_time), B->C->D
    travel (travel_time, one s-curve over the polyline B-C-D so the speed stays smooth through C),
    D->E lower (lift_time), optional hold, then back E->A the same way; constant before 0 and
    after the end.

    Args:
        t: (N,) sample times, s.
        waypoints: (5, 3) A..E, m.
        offset: optional (3,) shift of all waypoints, m.
    """
    W = np.asarray(waypoints, dtype=float) + (0.0 if offset is None else np.asarray(offset, float))
    t = np.asarray(t, dtype=float)
    L = lift_time
    half = 2 * L + travel_time
    tt = np.where(t <= half + hold, t, np.maximum(2 * half + hold - t, 0.0))   # way back = mirror
    sign = np.where(t <= half + hold, 1.0, -1.0)
    # travel B->C->D: arc-length parameterised polyline with one s-curve
    seg = np.linalg.norm(np.diff(W[1:4], axis=0), axis=1)
    knots_s = np.concatenate([[0.0], np.cumsum(seg)]) / seg.sum()
    x = np.empty((len(t), 3))
    v = np.zeros((len(t), 3))
    a = np.zeros((len(t), 3))
    lift = tt < L
    xl, vl, al = _piecewise(tt[lift], np.array([0.0, L]), W[[0, 1]])
    x[lift], v[lift], a[lift] = xl, vl, al
    trav = (tt >= L) & (tt < L + travel_time)
    s, ds, dds = scurve((tt[trav] - L) / travel_time)
    k = np.clip(np.searchsorted(knots_s, s, side="right") - 1, 0, 1)
    dir_ = (W[2:4] - W[1:3])[k] / (seg[k] / seg.sum())[:, None]     # dX/ds per segment
    x[trav] = W[1:3][k] + (s - knots_s[k])[:, None] * dir_
    v[trav] = (ds / travel_time)[:, None] * dir_
    a[trav] = (dds / travel_time ** 2)[:, None] * dir_
    low = tt >= L + travel_time
    xd, vd, ad = _piecewise(np.minimum(tt[low], half), np.array([L + travel_time, half]), W[[3, 4]])
    x[low], v[low], a[low] = xd, vd, ad
    return Trajectory(t, x, v * sign[:, None], a)


def sample_trajectory(duration: float = 60.0, rate: float = 100.0, **kwargs) -> Trajectory:
    """The test trajectory sampled at ``rate`` Hz for ``duration`` s (60 s = A->E->A)."""
    t = np.arange(int(round(duration * rate)) + 1) / rate
    return pick_and_place(t, **kwargs)


class ReferenceTable:
    """The test trajectory as a live reference: held at A for ``settle`` s, then
    :func:`pick_and_place` at ``speed`` times its nominal pace, then held at A for ever.

    Tabulated once at ``rate`` Hz up to 1 s after the return (:meth:`at` of a stamp on the grid is
    a table look-up: evaluating the s-curve per sample cost ~0.13 ms of a 1 kHz step); stamps off
    the grid are evaluated directly, stamps past the table hold its last row.

    Args:
        rate: Hz of the stamps that will be asked for.
        settle: s held at the start point A before the trajectory starts.
        speed: time scale of the s-curve (2 = twice as fast).
    """

    def __init__(self, rate: float, settle: float = 1.0, speed: float = 1.0):
        self.rate, self.settle, self.speed = float(rate), float(settle), float(speed)
        end = self.settle + 60.0 / self.speed + 1.0
        grid = np.arange(int(end * self.rate) + 2) / self.rate
        tr = pick_and_place(np.maximum(0.0, grid - self.settle) * self.speed)
        self._table = (tr.position, tr.velocity * self.speed, tr.acceleration * self.speed ** 2)

    def at(self, t: float):
        """(position (3,) m, velocity (3,) m/s, acceleration (3,) m/s^2) of the reference at ``t`` s."""
        k = int(round(t * self.rate))
        pos, vel, acc = self._table
        if k < len(pos) and abs(k / self.rate - t) < 1e-9:
            return pos[k], vel[k], acc[k]
        if k >= len(pos):           # the table ends 1 s after the return to A: held there since
            return pos[-1], vel[-1], acc[-1]
        tr = pick_and_place(np.array([max(0.0, t - self.settle) * self.speed]))
        return tr.position[0], tr.velocity[0] * self.speed, tr.acceleration[0] * self.speed ** 2

    def rows(self, k0: int, count: int):
        """(stamps (count,) s, positions, velocities, accelerations (count, 3)) of the grid stamps
        ``(k0 + j) / rate``, j < count: :meth:`at` of each, as arrays (rows past the table hold
        its last row)."""
        k = np.minimum(np.arange(k0, k0 + count), len(self._table[0]) - 1)
        k = np.maximum(k, 0)
        pos, vel, acc = self._table
        return np.arange(k0, k0 + count) / self.rate, pos[k], vel[k], acc[k]
