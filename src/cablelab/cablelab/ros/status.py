"""Book-keeping the nodes report on /diagnostics (ROS-free): problems joined into one status line,
samples skipped with the reason, and the per-sample processing time.
"""
from __future__ import annotations

import time

import numpy as np

from .inputs import WARN

__all__ = ["add_problem", "SkipLog", "Latency", "sim_values"]


def add_problem(level: int, msg: str, new_level: int, text: str) -> tuple[int, str]:
    """``(level, msg)`` raised to ``new_level`` with ``text`` joined to the message (``"ok"`` is
    replaced, anything else kept before ``"; text"``)."""
    return max(level, new_level), (text if msg == "ok" else f"{msg}; {text}")


class SkipLog:
    """Samples a node skipped (no output) and the last reason; recent skips are a WARN."""

    def __init__(self, recent: float = 2.0):
        self.skipped = 0
        self.last_problem = ""
        self.last_skip = -1e9           # wall time (monotonic) of the last skipped sample
        self.recent = recent

    def skip(self, problem: str) -> None:
        self.skipped += 1
        self.last_skip = time.monotonic()
        self.last_problem = problem

    def is_recent(self) -> bool:
        """A sample was skipped in the last ``recent`` s wall (and the reason is known)."""
        return bool(self.last_problem) and time.monotonic() - self.last_skip < self.recent

    def warn(self, level: int, msg: str) -> tuple[int, str]:
        """:func:`add_problem` with the last reason when a sample was skipped recently."""
        return add_problem(level, msg, WARN, self.last_problem) if self.is_recent() else (level, msg)


class Latency:
    """Wall time of each processed sample (bounded: the oldest half dropped past ``keep``)."""

    def __init__(self, keep: int = 100000):
        self.samples: list[float] = []
        self.keep = keep

    def add(self, seconds: float) -> None:
        self.samples.append(seconds)
        if len(self.samples) > self.keep:
            del self.samples[:self.keep // 2]

    def since(self, t0: float) -> None:
        """Add the time since ``t0`` (a :func:`time.perf_counter` reading)."""
        self.add(time.perf_counter() - t0)

    def __len__(self) -> int:
        return len(self.samples)

    def report(self, values: dict) -> dict:
        """``values["latency p99 ms"]`` over the last 1000 samples (nothing before the first)."""
        if self.samples:
            values["latency p99 ms"] = f"{1000 * np.percentile(np.asarray(self.samples[-1000:]), 99):.3f}"
        return values


def sim_values(values: dict, t: float | None = None, lock=None) -> dict:
    """A simulator's own /diagnostics values: ``sim time s`` (when ``t`` is given) and, with a
    :class:`~cablelab.ros.lockstep.LockStep`, the answers to earlier states it ignored."""
    if t is not None:
        values["sim time s"] = f"{t:.3f}"
    if lock is not None:
        values["stale answers ignored (lock-step)"] = str(lock.stale_answers)
    return values
