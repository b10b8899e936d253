"""Input checking for node callbacks: NaN, wrong length and stale inputs (ROS-free).

A node registers each input with the length it expects and how old it may get; every callback
passes its values through :meth:`InputMonitor.accept`, which rejects bad messages (counting them
and remembering why) instead of letting them reach the control or estimation law. The node
reports :meth:`InputMonitor.status` on /diagnostics.
"""
from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

OK, WARN, ERROR = 0, 1, 2


@dataclass
class InputState:
    """Book-keeping of one input (times in s of the node's clock)."""

    name: str
    timeout: float
    length: int | None = None
    received: int = 0
    rejected: int = 0
    last_time: float | None = None
    last_problem: str = ""


def _problem(length: int | None, size: int, finite) -> str:
    """What is wrong with a message of ``size`` values for an input of ``length`` ("" if
    nothing); ``finite()`` says whether its values are finite (asked last)."""
    if size == 0:
        return "empty"
    if length is not None and size != length:
        return f"wrong length {size}, expected {length}"
    return "" if finite() else "NaN or infinite value"


@dataclass
class InputMonitor:
    """Tracks every input of a node. ``required`` inputs make the status ERROR when stale."""

    inputs: dict[str, InputState] = field(default_factory=dict)
    required: set[str] = field(default_factory=set)

    def add(self, name: str, timeout: float = 0.5, length: int | None = None,
            required: bool = True) -> None:
        """Register an input: ``timeout`` s before it counts as stale, expected ``length``."""
        self.inputs[name] = InputState(name, timeout, length)
        if required:
            self.required.add(name)

    def set_length(self, name: str, length: int | None) -> None:
        self.inputs[name].length = length

    def accept(self, name: str, values, now: float) -> bool:
        """Check one message's values; True if usable. Bad values are counted, not raised."""
        st = self.inputs[name]
        arr = np.asarray(values, dtype=float) if values is not None else np.zeros(0)
        problem = _problem(st.length, arr.size, lambda: np.isfinite(arr).all())
        if problem:
            st.rejected += 1
            st.last_problem = problem
            return False
        st.received += 1
        st.last_time = now
        return True

    def accept_rows(self, name: str, rows, now: float, present=None) -> np.ndarray:
        """:meth:`accept` of k messages at once: ``rows`` (k, m) their values, ``present`` (k,)
        False where a message had none ("empty"). Returns the (k,) mask of the usable ones and
        leaves the counts, time and last problem as k calls of :meth:`accept` in row order would."""
        st = self.inputs[name]
        rows = np.asarray(rows, dtype=float)
        if len(rows) == 0:
            return np.zeros(0, bool)
        rows = rows.reshape(len(rows), -1)
        k, m = rows.shape
        empty = np.ones(k, bool) if m == 0 else ~np.asarray(True if present is None else present, bool)
        empty = np.broadcast_to(empty, (k,))
        wrong = ~empty & (st.length is not None and m != st.length)
        bad = ~empty & ~wrong & ~np.isfinite(rows).all(1)
        ok = ~(empty | wrong | bad)
        n_ok = int(ok.sum())
        if n_ok < k:
            j = int(np.flatnonzero(~ok)[-1])
            st.last_problem = _problem(st.length, 0 if empty[j] else m, lambda: False)
            st.rejected += k - n_ok
        if n_ok:
            st.received += n_ok
            st.last_time = now
        return ok

    def age(self, name: str, now: float) -> float:
        """Seconds since the last good message (inf if none yet)."""
        st = self.inputs[name]
        return float("inf") if st.last_time is None else now - st.last_time

    def stale(self, now: float) -> list[str]:
        """Inputs whose last good message is older than their timeout (or never came)."""
        return [n for n, st in self.inputs.items() if self.age(n, now) > st.timeout]

    def fresh(self, name: str, now: float) -> bool:
        return self.age(name, now) <= self.inputs[name].timeout

    def status(self, now: float) -> tuple[int, str, dict[str, str]]:
        """(level OK/WARN/ERROR, one-line message, key values) for /diagnostics."""
        stale = self.stale(now)
        level, msgs = OK, []
        bad_required = [n for n in stale if n in self.required]
        if bad_required:
            level = ERROR
            msgs.append("stale input: " + ", ".join(bad_required))
        elif stale:
            level = WARN
            msgs.append("stale optional input: " + ", ".join(stale))
        rejected = [n for n, st in self.inputs.items() if st.rejected]
        if rejected:
            level = max(level, WARN)
            msgs.append("rejected messages on " + ", ".join(
                f"{n} ({self.inputs[n].last_problem})" for n in rejected))
        values = {}
        for n, st in self.inputs.items():
            values[f"{n} received"] = str(st.received)
            values[f"{n} rejected"] = str(st.rejected)
            age = self.age(n, now)
            values[f"{n} age s"] = "never" if age == float("inf") else f"{age:.3f}"
        return level, "; ".join(msgs) or "ok", values
