"""The latest samples of a stream, looked up by stamp.

A set-point stream may run ahead of the states it goes with (a trajectory generator streams the
set-point of stamp t + dt together with the state of stamp t, so that the next state finds its
set-point already delivered). A consumer then needs "the newest sample not newer than t", not
"the newest sample". :class:`StampedBuffer` keeps the last ``size`` samples in stamp order.
"""
from __future__ import annotations

from collections import deque

__all__ = ["StampedBuffer"]


class StampedBuffer:
    """The last ``size`` (stamp, value) pairs, stamps in s.

    Args:
        size: samples kept: more than the lead of the stream over the samples it is looked up
            for (the simulator streams the reference 50 ms, 50 samples at 1 kHz, ahead).
        tol: stamps within ``tol`` s count as equal (float stamps from nanosecond fields).
    """

    def __init__(self, size: int = 2048, tol: float = 1e-9):
        self._items: deque = deque(maxlen=size)
        self.tol = tol

    def push(self, t: float, value) -> None:
        """Add a sample; an older stamp than the newest one restarts the buffer (a stream that
        went back in time, e.g. a restarted simulator)."""
        if self._items and t < self._items[-1][0] - self.tol:
            self._items.clear()
        self._items.append((t, value))

    def __bool__(self) -> bool:
        return bool(self._items)

    @property
    def newest(self) -> float | None:
        """Stamp of the newest sample (None when empty)."""
        return self._items[-1][0] if self._items else None

    def at(self, t: float):
        """(stamp, value) of the newest sample with stamp <= t, else the oldest one kept (the
        stream started after t); None when empty."""
        if not self._items:
            return None
        for item in reversed(self._items):
            if item[0] <= t + self.tol:
                return item
        return self._items[0]

    def after(self, t: float):
        """(stamp, value) of the oldest sample with stamp > t (the next one after t), None when
        there is none yet. (Searched from the newest: the samples looked up are a lead behind it.)"""
        nxt = None
        for item in reversed(self._items):
            if item[0] <= t + self.tol:
                break
            nxt = item
        return nxt
