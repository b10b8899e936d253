"""A control loop the ros2_control way: read hardware -> update the law -> write hardware, once
per period, at absolute deadlines, in one thread (no DDS between the robot and its controller).

:class:`ControlLoop` runs a :class:`~cablelab.hardware.HardwareInterface` and a
:class:`ControlLaw`. Each period it sleeps to the absolute deadline ``start + k / rate``
(``clock_nanosleep(CLOCK_MONOTONIC, TIMER_ABSTIME)``: no drift, however long the body took),
then ``state = hardware.read()``, ``command = law.update(state)``, ``hardware.write(command)``:
that is the deadline path, timed as the loop body. Everything else (publishing the state for
recorders and estimators, taking a new estimate, preparing the next reference) goes in the
``after_write(state, command)`` hook, after the command is out; the hook can ask
:meth:`ControlLoop.behind` whether the next deadline has already passed, and leave what can wait
(taking inputs, diagnostics, planning ahead) to a period with time to spare, so that catching up
after a stall costs each period no more than its body.

Cycles are counted as ``bench/rcl_floor/floor.c`` counts its bare timer, so the two compare: a
wake-up a period or more after its deadline is a *late* cycle (the loop then runs the periods
already due back to back: a simulated plant keeps pace with the wall clock), more than
``max_behind`` periods behind the periods already past are *dropped* (skipped); missed cycles =
late + dropped, counted after ``warmup`` s. :class:`LoopStats` also keeps the body's p99 in the
worst 1 s window and the realtime factor (hardware stamps / wall time).

No ROS here; the ``control_loop`` executable (:mod:`cablelab.ros.control_loop`) adds the
publishers and /diagnostics around it.
"""
from __future__ import annotations

import ctypes
import time
from array import array
from typing import Callable, Protocol, runtime_checkable

import numpy as np

from .hardware import HardwareInterface, HardwareState

__all__ = ["ControlLaw", "ControlLoop", "LoopStats", "sleep_until"]


@runtime_checkable
class ControlLaw(Protocol):
    """The controller of a control loop: ``update(state)`` returns the command (n,) for the
    hardware (or None: no valid command this period, the hardware brakes) and leaves why in
    ``status``, a list of (level 0 OK / 1 WARN / 2 ERROR, message), as
    :class:`~cablelab.plants.cdpr.live.LiveController` does."""

    status: list

    def update(self, state: HardwareState) -> np.ndarray | None: ...


class _Timespec(ctypes.Structure):
    _fields_ = [("tv_sec", ctypes.c_long), ("tv_nsec", ctypes.c_long)]


def _make_sleep_until() -> Callable[[float], None]:
    """``sleep_until(t)``: sleep to ``time.monotonic() == t`` with clock_nanosleep's absolute
    mode where libc has it (ctypes releases the GIL), else ``time.sleep`` of the difference."""
    try:
        fn = ctypes.CDLL(None, use_errno=True).clock_nanosleep
        fn.argtypes = [ctypes.c_int, ctypes.c_int, ctypes.POINTER(_Timespec), ctypes.c_void_p]
        fn.restype = ctypes.c_int
    except (OSError, AttributeError):
        def sleep_until(t: float) -> None:
            dt = t - time.monotonic()
            if dt > 0:
                time.sleep(dt)
        return sleep_until
    ts = _Timespec()
    ref = ctypes.byref(ts)

    def sleep_until(t: float) -> None:       # CLOCK_MONOTONIC = 1 (time.monotonic's), TIMER_ABSTIME = 1
        sec = int(t)
        ts.tv_sec, ts.tv_nsec = sec, int((t - sec) * 1e9)
        fn(1, 1, ref, None)                  # EINTR (a signal): return early, the caller re-checks
    return sleep_until


sleep_until = _make_sleep_until()


class LoopStats:
    """Cycle accounting of a loop at ``rate`` Hz (see the module docstring).

    Attributes: ``cycles`` (counted, after the warm-up), ``late``, ``dropped``,
    ``missed_cycles`` (late + dropped), ``worst_p99`` (s: the body's p99 in the worst full 1 s
    window), ``realtime_factor``, and ``bodies`` (every counted body time, s, up to
    ``keep`` of them).
    """

    def __init__(self, rate: float, keep: int = 1_200_000):
        self.rate = float(rate)
        self.window = max(1, int(round(rate)))
        self.cycles = self.late = self.dropped = 0
        self.bodies = array("d")
        self.keep = int(keep)
        self.worst_p99 = 0.0
        self.last_p99 = 0.0
        self.wakeup_max = 0.0       # s: the latest start after a deadline
        self._win = np.empty(self.window)
        self._nwin = 0
        self._first = None          # (wall, stamp) of the first counted cycle
        self._last = None

    @property
    def missed_cycles(self) -> int:
        return self.late + self.dropped

    @property
    def realtime_factor(self) -> float | None:
        if self._first is None or self._last is None or self._last[0] <= self._first[0]:
            return None
        return (self._last[1] - self._first[1]) / (self._last[0] - self._first[0])

    def record(self, late: bool, body: float, wall: float, stamp: float, behind: float = 0.0) -> None:
        """One counted cycle: late or not, its body time (s), wake-up wall time and stamp, and
        how far after its deadline it started (s)."""
        self.cycles += 1
        self.late += bool(late)
        if behind > self.wakeup_max:
            self.wakeup_max = behind
        if len(self.bodies) < self.keep:
            self.bodies.append(body)
        self._win[self._nwin] = body
        self._nwin += 1
        if self._nwin == self.window:         # a full 1 s window: its p99
            self.last_p99 = float(np.percentile(self._win, 99))
            self.worst_p99 = max(self.worst_p99, self.last_p99)
            self._nwin = 0
        if self._first is None:
            self._first = (wall, stamp)
        self._last = (wall, stamp)

    def summary(self) -> dict:
        """The figures as a JSON-able dict (times in ms)."""
        b = np.frombuffer(self.bodies, dtype=float) if len(self.bodies) else np.zeros(1)
        return {"rate_hz": self.rate, "cycles": self.cycles, "missed_cycles": self.missed_cycles,
                "late": self.late, "dropped": self.dropped,
                "p99_ms": 1e3 * (self.worst_p99 if self.worst_p99 else float(np.percentile(b, 99))),
                "p99_all_ms": 1e3 * float(np.percentile(b, 99)), "median_ms": 1e3 * float(np.median(b)),
                "realtime_factor": self.realtime_factor, "wakeup_max_ms": 1e3 * self.wakeup_max}


class ControlLoop:
    """read -> update -> write at ``rate`` Hz on absolute deadlines (module docstring).

    Args:
        hardware: the robot or its simulator (:class:`~cablelab.hardware.HardwareInterface`).
        law: the controller (:class:`ControlLaw`).
        rate: Hz.
        after_write: optional ``fn(state, command)`` called after each write, off the deadline
            path (publish, take estimates, prepare the next period).
        warmup: s of cycles not counted at the start.
        max_behind: periods behind after which the past periods are skipped instead of run.
        clock, sleep: monotonic clock (s) and ``sleep_until(t)`` (for tests).
    """

    def __init__(self, hardware: HardwareInterface, law: ControlLaw, rate: float, *, after_write=None,
                 warmup: float = 1.0, max_behind: int = 20, clock=time.monotonic, sleep=None):
        if not rate > 0:
            raise ValueError(f"control loop rate must be > 0 Hz, got {rate}")
        self.hardware, self.law, self.rate = hardware, law, float(rate)
        self.period = 1.0 / self.rate
        self.after_write = after_write
        self.warm = int(round(warmup * self.rate))
        self.max_behind = int(max_behind)
        self.clock = clock
        self.sleep = sleep or sleep_until
        self.stats = LoopStats(self.rate)
        self.k = 0                  # index of the next period
        self.start_wall = None
        self.state = None           # last state read
        self.command = None         # last command written (None: no valid command)
        self.started = False

    def start(self) -> None:
        """Start the hardware; the first deadline is now."""
        self.hardware.start()
        self.started = True
        self.start_wall = self.clock()
        self.k = 0

    def stop(self) -> None:
        """Stop the hardware (once)."""
        if self.started:
            self.started = False
            self.hardware.stop()

    def behind(self) -> bool:
        """True when the next period's deadline has passed (the loop is catching up)."""
        return self.started and self.clock() >= self.start_wall + self.k * self.period

    def cycle(self) -> tuple[HardwareState, np.ndarray | None]:
        """One untimed read -> update -> write (the body, also for tests)."""
        state = self.hardware.read()
        command = self.law.update(state)
        self.hardware.write(command)
        self.state, self.command = state, command
        return state, command

    def run_until(self, wall: float, stop: Callable[[], bool] | None = None) -> None:
        """Run the periods whose deadlines fall before ``wall`` (monotonic s), or until ``stop()``."""
        if not self.started:
            self.start()
        T, clock = self.period, self.clock
        while True:
            due = self.start_wall + self.k * T
            if due >= wall or (stop is not None and stop()):
                return
            self.sleep(due)
            woke = clock()
            if woke < due:                          # a signal woke the sleep: check stop, sleep again
                continue
            behind = woke - due
            counting = self.k >= self.warm
            if behind > self.max_behind * T:        # too far behind: skip the periods already past
                skip = int(behind / T)
                if counting:
                    self.stats.dropped += skip
                self.k += skip
                continue
            state, command = self.cycle()
            if counting:
                self.stats.record(behind >= T, clock() - woke, woke, state.t, behind)
            self.k += 1
            if self.after_write is not None:
                self.after_write(state, command)
