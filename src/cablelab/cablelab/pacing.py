"""Pacing a replay by a bag's log times without waiting through its gaps.

A bag whose clock jumped forward (1e6 s inside a 20 s recording) or that paused for minutes
would make a replay paced by log times sleep just as long. :func:`replay_times` gives each
message the time it is due in the replay: its log time minus every gap before it, a gap being a
step longer than :data:`GAP_PERIODS` typical steps (and at least :data:`MIN_GAP_S`); each gap is
replayed as one typical step. The gaps are returned too (the replayer warns once and lets its
/clock jump over them).
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np

#: a step longer than this many median steps (and than MIN_GAP_S) is a gap
GAP_PERIODS = 5.0
#: pauses shorter than this are always replayed as recorded
MIN_GAP_S = 1.0


@dataclass
class ReplayGaps:
    """The gaps of a schedule: count, longest (s) and where it starts (s of log time)."""

    count: int = 0
    longest: float = 0.0
    at: float = 0.0
    threshold_ns: int = 0

    def warning(self) -> str:
        return (f"{self.count} gap(s) in the bag's log times (longest {self.longest:.6g} s at "
                f"t = {self.at:.6g} s): replayed without waiting, the clock jumps over them")


def replay_times(log_ns) -> tuple[np.ndarray, ReplayGaps]:
    """``(due_ns, gaps)``: for sorted log times (N,) in ns, the replay time each message is due
    (ns from the same origin, gaps shortened to one median step) and the gaps found."""
    t = np.asarray(log_ns, dtype=np.int64)
    if t.size < 2:
        return t.copy(), ReplayGaps()
    dt = np.diff(t)
    pos = dt[dt > 0]
    step = int(np.median(pos)) if pos.size else 0
    threshold = max(int(GAP_PERIODS * step), int(MIN_GAP_S * 1e9))
    big = dt > threshold
    gaps = ReplayGaps(threshold_ns=threshold)
    if not big.any():
        return t.copy(), gaps
    cut = np.where(big, dt - step, 0)
    due = t - np.concatenate([[0], np.cumsum(cut)])
    k = int(np.argmax(np.where(big, dt, -1)))
    gaps.count, gaps.longest, gaps.at = int(big.sum()), float(dt[k]) * 1e-9, float(t[k]) * 1e-9
    return due, gaps
