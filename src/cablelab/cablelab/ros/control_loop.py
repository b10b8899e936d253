"""The ``control_loop`` node shell: a :class:`cablelab.control_loop.ControlLoop` in a ROS process.

ros2_control's shape: the hardware (a simulator or a driver, :mod:`cablelab.hardware`) and the
controller law run in this one process, in one thread, on absolute deadlines; DDS only carries
what other nodes observe. After each write (off the deadline path) the node publishes the
period's state, command and reference for recorders and estimators, takes what arrived on its
input topics without waiting (e.g. a live estimate: ``fastspin.take_newest`` on a keep-last-1
queue that no executor waits on), and publishes /diagnostics once a second.

A plant's loop node (``plants/<plant>/nodes/control_loop.py``) subclasses :class:`ControlLoopNode`:
it builds its hardware and law and calls :meth:`ControlLoopNode.setup_loop`, and overrides
:meth:`~ControlLoopNode.publish_cycle` (its topics), :meth:`~ControlLoopNode.take_inputs` and
:meth:`~ControlLoopNode.after_cycle` (e.g. prepare the next period's reference terms).

The node is its own executor (:class:`LoopSpinner`: ``spin_once(timeout)`` runs the periods due
within ``timeout``), so :func:`cablelab.ros.runner.run_node` runs it like any node: SIGINT or
SIGTERM stop it within 0.1 s; at shutdown the hardware is stopped and one JSON line with the
cycle figures is printed (``{"node": "control_loop", "missed_cycles", "late", "dropped",
"p99_ms", ...}``, read by ``bench/bench_realtime.py``).

ROS parameters of every loop: ``rate`` (Hz, 1000), ``duration`` (s of hardware stamps after which
the node exits, 0 = run until stopped), ``warmup`` (s not counted in the cycle figures, 1),
``publish_thread`` (false: publish in the loop's thread after the write; true: hand the samples
to a publisher thread through a queue), ``input_period`` (s between non-blocking takes of the
input topics, 0.01), and the placement parameters of every node (``cpu_affinity``, ``niceness``,
``sched_idle``, ``sched_slice``, ``rt_priority``: :meth:`PlantNode.use_fast_executor`).
"""
from __future__ import annotations

import json
import queue
import sys
import threading
import time

from ..control_loop import ControlLoop
from ..errors import CablelabError
from .inputs import WARN
from .plant_node import PlantNode

__all__ = ["ControlLoopNode", "LoopSpinner"]

_DIAG = object()      # queue marker: publish /diagnostics
_STOP = object()      # queue marker: end of the publisher thread


class LoopSpinner:
    """The executor :func:`~cablelab.ros.runner.run_node` spins a :class:`ControlLoopNode` with:
    ``spin_once(timeout_sec)`` runs the node's periods due in the next ``timeout_sec`` s."""

    def __init__(self):
        self.node = None

    def add_node(self, node) -> bool:
        self.node = node
        return True

    def spin_once(self, timeout_sec: float | None = None) -> None:
        node = self.node
        node.loop.run_until(time.monotonic() + (0.1 if timeout_sec is None else timeout_sec),
                            stop=lambda: node.done)

    def shutdown(self, timeout_sec: float | None = None) -> bool:
        return True


class ControlLoopNode(PlantNode):
    """Base of a plant's control-loop node (module docstring)."""

    def __init__(self, name: str = "control_loop"):
        super().__init__(name, start_parameter_services=False)
        self.rate = float(self.param("rate", 1000.0))
        self.duration = float(self.param("duration", 0.0))
        self.warmup = float(self.param("warmup", 1.0))
        self.publish_thread = bool(self.param("publish_thread", False))
        input_period = float(self.param("input_period", 0.01))
        if not self.rate > 0 or self.duration < 0 or self.warmup < 0 or input_period < 0:
            raise CablelabError(f"{name}: parameters rate > 0, duration >= 0, warmup >= 0 and "
                                "input_period >= 0 expected")
        self.take_every = max(1, int(round(input_period * self.rate)))
        self.loop: ControlLoop | None = None
        self.done = False
        self.commands = 0           # valid commands written
        self.no_command = 0         # periods without a valid command (the hardware braked)
        self.last_problem = ""
        self._cycle = 0
        self._next_diag = 0.0
        self._queue = None
        self._thread = None
        self._cpu0 = None           # (process CPU s, cycles) when the counted cycles started

    # ------------------------------------------------------------------ set-up
    def setup_loop(self, hardware, law) -> None:
        """Build the loop over ``hardware`` and ``law``, apply the placement parameters, start
        /diagnostics (call last in the subclass's ``__init__``)."""
        self.hardware, self.law = hardware, law
        self.loop = ControlLoop(hardware, law, self.rate, after_write=self._after_write, warmup=self.warmup)
        self.use_fast_executor()
        self.start_diagnostics()
        if self.publish_thread:
            # a thread that holds the GIL keeps the loop's thread waiting after its wake-up for up
            # to the interpreter's switch interval (5 ms by default): at most a tenth of a period
            sys.setswitchinterval(min(sys.getswitchinterval(), 0.1 / self.rate))
            self._queue = queue.SimpleQueue()
            self._thread = threading.Thread(target=self._publisher, name="control_loop publisher", daemon=True)
            self._thread.start()

    def executor_factory(self):
        return LoopSpinner()

    # ------------------------------------------------------------------ hooks
    def publish_cycle(self, state, command) -> None:
        """Publish the period's state and command (override)."""

    def take_inputs(self) -> None:
        """Take what arrived on the input topics without waiting (override)."""

    def after_cycle(self, state) -> None:
        """Work for the next period, after the inputs were taken (override)."""

    # ------------------------------------------------------------------ the loop's tail
    def _after_write(self, state, command) -> None:
        if command is None:
            self.no_command += 1
            status = getattr(self.law, "status", None)
            self.last_problem = status[-1][1] if status else "no command"
        else:
            self.commands += 1
        if self._queue is not None:
            self._queue.put((state, command))
        else:
            self.publish_cycle(state, command)
        self._cycle += 1
        if self._cpu0 is None and self.loop.stats.cycles:
            self._cpu0 = (time.process_time(), self.loop.stats.cycles)    # the counted cycles start
        if self._cycle % self.take_every == 0:
            self.take_inputs()
        self.after_cycle(state)
        now = time.monotonic()
        if now >= self._next_diag:
            self._next_diag = now + 1.0
            if self._queue is not None:
                self._queue.put(_DIAG)
            else:
                self.diag.publish()
        if self.duration and state.t >= self.duration:
            self.done = True

    def _publisher(self) -> None:
        q = self._queue
        while True:
            item = q.get()
            if item is _STOP:
                return
            try:
                if item is _DIAG:
                    self.diag.publish()
                else:
                    self.publish_cycle(*item)
            except Exception as exc:  # noqa: BLE001 - a publish error must not end the publishing
                self.get_logger().error(f"publishing: {exc}")

    # ------------------------------------------------------------------ status and end
    def extend_status(self, level, msg, values):
        loop = self.loop
        if loop is not None:
            s = loop.stats
            rt = s.realtime_factor
            values.update({"cycles": str(s.cycles), "missed cycles": str(s.missed_cycles),
                           "late cycles": str(s.late), "dropped cycles": str(s.dropped),
                           "loop body p99 ms": f"{1e3 * s.last_p99:.3f}",
                           "loop body worst p99 ms": f"{1e3 * s.worst_p99:.3f}",
                           "realtime factor": "-" if rt is None else f"{rt:.4f}",
                           "commands": str(self.commands), "periods without command": str(self.no_command)})
            status = getattr(self.law, "status", None)
            if status and status[-1][0] > 0:
                level = max(level, status[-1][0])
                msg = status[-1][1] if msg == "ok" else f"{msg}; {status[-1][1]}"
            if loop.command is None and loop.state is not None:
                level = max(level, WARN)
        return level, msg, values

    def summary(self) -> dict:
        """The cycle figures (:meth:`LoopStats.summary`) and the node's counts."""
        out = {"node": "control_loop"} | self.loop.stats.summary()
        out.update(commands=self.commands, periods_without_command=self.no_command)
        if self._cpu0 is not None and self.loop.stats.cycles > self._cpu0[1]:   # all threads of the process
            out["cpu_per_cycle_ms"] = 1e3 * (time.process_time() - self._cpu0[0]) / (self.loop.stats.cycles
                                                                                  - self._cpu0[1])
        return out

    def shutdown(self) -> None:
        if self._thread is not None:
            self._queue.put(_STOP)
            self._thread.join(timeout=5.0)
        if self.loop is not None:
            self.loop.stop()
            if self.loop.start_wall is not None:       # the hardware started: there are figures
                print(json.dumps(self.summary()), flush=True)
            sys.stdout.flush()

