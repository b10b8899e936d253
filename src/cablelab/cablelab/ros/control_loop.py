"""The ``control_loop`` node shell: a :class:`cablelab.control_loop.ControlLoop` in a ROS process.

ros2_control's shape: the hardware (a simulator or a driver, :mod:`cablelab.hardware`) and the
controller law run in this one process, in one thread, on absolute deadlines; DDS only carries
what other nodes observe. After each write (off the deadline path) the node hands the period's
state and command to its publisher (parameter ``publisher``: by default a child process fed
through a shared-memory ring, :mod:`cablelab.sample_ring` and :mod:`cablelab.ros.loop_publisher`,
so that publishing costs the loop's process one record copy and never holds its GIL at a
deadline; or a thread of this process; or this thread), takes what arrived on its input topics
without waiting (e.g. a live estimate: ``fastspin.take_newest`` on a keep-last-1 queue that no
executor waits on), and publishes /diagnostics once a second; while the loop is catching up after
a stall (:meth:`ControlLoop.behind`) those two wait for the first period with time to spare.

A plant's loop node (``plants/<plant>/nodes/control_loop.py``) subclasses :class:`ControlLoopNode`:
it builds its hardware and law and calls :meth:`ControlLoopNode.setup_loop`, and overrides
:meth:`~ControlLoopNode.cycle_publisher` (its topics), :meth:`~ControlLoopNode.take_inputs` and
:meth:`~ControlLoopNode.after_cycle` (e.g. prepare the next period's reference terms).

The node is its own executor (:class:`LoopSpinner`: ``spin_once(timeout)`` runs the periods due
within ``timeout``), so :func:`cablelab.ros.runner.run_node` runs it like any node: SIGINT or
SIGTERM stop it within 0.1 s; at shutdown the hardware is stopped and one JSON line with the
cycle figures is printed (``{"node": "control_loop", "missed_cycles", "late", "dropped",
"p99_ms", ...}``, read by ``bench/bench_realtime.py``).

ROS parameters of every loop: :data:`LOOP_PARAMETERS`, and the placement parameters of every
node (``cpu_affinity``, ``niceness``, ``sched_idle``, ``sched_slice``, ``rt_priority``:
:meth:`PlantNode.use_fast_executor`).
"""
from __future__ import annotations

import json
import os
import queue
import subprocess
import sys
import threading
import time

from ..control_loop import ControlLoop
from .inputs import ERROR, WARN
from .params import Param
from .plant_node import PlantNode
from .status import add_problem

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


#: parameters of every control loop (a plant's loop adds its own: ``merge(LOOP_PARAMETERS, ...)``)
LOOP_PARAMETERS = (
    Param("rate", 1000.0, "loop rate (one read, update, write per period)", "Hz", ge=1.0, le=100000.0),
    Param("duration", 0.0, "time of hardware stamps after which the node exits (0 = run until "
          "stopped)", "s", ge=0.0),
    Param("warmup", 1.0, "time not counted in the cycle figures", "s", ge=0.0, le=3600.0),
    Param("publisher", "process", "who publishes each period's samples: process (a child process fed "
          "through shared memory, at lower CPU priority), thread (a thread of the loop's process, "
          "fed through a queue) or loop (the loop's thread, after the write)",
          choices=("process", "thread", "loop")),
    Param("publish_batch", 0.005, "time between the publisher's wake-ups (process and thread: the "
          "samples written since are published in one go)", "s", ge=0.0, le=1.0),
    Param("publisher_niceness", 5, "niceness of the publisher process (0-19: below the loop's CPU "
          "priority)", ge=0, le=19),
    Param("publish_buffer", 10.0, "samples the publisher process may fall behind before the loop "
          "counts them lost (shared-memory ring), in time of the loop", "s", ge=0.01, le=600.0),
    Param("input_period", 0.01, "time between non-blocking takes of the input topics", "s",
          ge=0.0, le=10.0),
)


class ControlLoopNode(PlantNode):
    """Base of a plant's control-loop node (module docstring)."""

    def __init__(self, name: str = "control_loop"):
        super().__init__(name, start_parameter_services=False)
        v = self.declare_params(LOOP_PARAMETERS)
        self.rate = v.rate
        self.duration = v.duration
        self.warmup = v.warmup
        self.publisher_mode = v.publisher
        self.publish_batch = v.publish_batch
        self.publisher_niceness = v.publisher_niceness
        self.publish_buffer = v.publish_buffer
        input_period = v.input_period
        self.take_every = max(1, int(round(input_period * self.rate)))
        self.loop: ControlLoop | None = None
        self.done = False
        self.commands = 0           # valid commands written
        self.no_command = 0         # periods without a valid command (the hardware braked)
        self.last_problem = ""
        self.cycle_pub = None       # the plant's cycle publisher (publisher loop or thread)
        self._cycle = 0
        self._take_due = False      # an input take waits for a period with time to spare
        self._next_diag = 0.0
        self._queue = None
        self._thread = None
        self._ring = None           # publisher process: the shared-memory ring, its layout, the child
        self._layout = None
        self._child = None
        self._child_cpu = None      # CPU s of the publisher process (when it ended)
        self._cpu0 = None           # (process CPU s, cycles) when the counted cycles started

    # ------------------------------------------------------------------ set-up
    def setup_loop(self, hardware, law) -> None:
        """Build the loop over ``hardware`` and ``law``, the publisher of the period's samples
        (:meth:`cycle_publisher`, in the mode of the ``publisher`` parameter), apply the placement
        parameters, start /diagnostics (call last in the subclass's ``__init__``)."""
        self.hardware, self.law = hardware, law
        self.loop = ControlLoop(hardware, law, self.rate, after_write=self._after_write, warmup=self.warmup)
        cls, config = self.cycle_publisher()
        if self.publisher_mode == "process":
            self._start_publisher_process(cls, config)
        else:
            self.cycle_pub = cls(self, config)
        self.use_fast_executor()
        self.start_diagnostics()
        if self.publisher_mode == "thread":
            # a thread that holds the GIL keeps the loop's thread waiting after its wake-up for up
            # to the interpreter's switch interval (5 ms by default): at most a tenth of a period
            sys.setswitchinterval(min(sys.getswitchinterval(), 0.1 / self.rate))
            self._queue = queue.SimpleQueue()
            self._thread = threading.Thread(target=self._publisher, name="control_loop publisher", daemon=True)
            self._thread.start()

    def _start_publisher_process(self, cls, config) -> None:
        from ..sample_ring import SampleRing
        from . import loop_publisher
        from .runner import split_ros_args

        self._layout = cls.layout(config)
        capacity = max(16, int(self.publish_buffer * self.rate))
        self._ring = SampleRing.create(self._layout.width, capacity)
        child = {"ring": self._ring.name, "layout": self._layout.to_dict(),
                 "publisher": f"{cls.__module__}:{cls.__qualname__}", "config": config,
                 "node": f"{self.get_name()}_publisher", "batch": self.publish_batch,
                 "niceness": self.publisher_niceness, "parent": os.getpid(),
                 "domain_id": self.context.get_domain_id()}
        self._child = loop_publisher.start(child, split_ros_args(sys.argv[1:])[1])

    def executor_factory(self):
        return LoopSpinner()

    # ------------------------------------------------------------------ hooks
    def cycle_publisher(self) -> tuple[type, dict]:
        """The class publishing the period's samples and its configuration (override).

        The class is built as ``cls(node, config)`` (in this process, or in the publisher process
        with a node of its own: ``config`` must be JSON) and has ``publish(state, command,
        cycle)`` and, for the publisher process, ``layout(config)`` (a classmethod returning the
        :class:`~cablelab.sample_ring.StateLayout` of the records: the extras it publishes)."""
        raise NotImplementedError(f"{type(self).__name__} must define cycle_publisher()")

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
        if self._ring is not None:
            row = self._ring.slot()
            if row is not None:          # (a full ring counts the sample lost)
                self._layout.pack(row, state, command)
                self._ring.commit()
        elif self._queue is not None:
            self._queue.put((state, command, self._cycle))
        else:
            self.cycle_pub.publish(state, command, self._cycle)
        self._cycle += 1
        if self._cpu0 is None and self.loop.stats.cycles:
            self._cpu0 = (time.process_time(), self.loop.stats.cycles)    # the counted cycles start
        if self._cycle % self.take_every == 0:
            self._take_due = True
        behind = self.loop.behind()
        if self._take_due and not behind:
            self._take_due = False
            self.take_inputs()
        self.after_cycle(state)
        now = time.monotonic()
        if now >= self._next_diag and not behind:
            self._next_diag = now + 1.0
            if self._queue is not None:
                self._queue.put(_DIAG)
            else:
                self.diag.publish()
        if self.duration and state.t >= self.duration:
            self.done = True

    def _publisher(self) -> None:
        """The publisher thread: every ``publish_batch`` s, everything queued since, in order."""
        q = self._queue
        while True:
            time.sleep(self.publish_batch)
            while True:
                try:
                    item = q.get_nowait()
                except queue.Empty:
                    break
                if item is _STOP:
                    return
                try:
                    if item is _DIAG:
                        self.diag.publish()
                    else:
                        self.cycle_pub.publish(*item)
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
        values["publisher"] = self.publisher_mode
        ring = self._ring
        if ring is not None:
            values.update({"samples awaiting publication": str(ring.backlog),
                           "samples lost (publisher behind)": str(ring.lost)})
            if self._child is not None and self._child.poll() is not None:
                level, msg = add_problem(level, msg, ERROR, f"publisher process ended (exit "
                                         f"{self._child.returncode}): samples not published")
            elif ring.lost:
                level, msg = add_problem(level, msg, WARN,
                                         f"{ring.lost} samples lost: the publisher process fell behind")
        return level, msg, values

    def summary(self) -> dict:
        """The cycle figures (:meth:`LoopStats.summary`) and the node's counts."""
        out = {"node": "control_loop"} | self.loop.stats.summary()
        out.update(commands=self.commands, periods_without_command=self.no_command)
        if self._cpu0 is not None and self.loop.stats.cycles > self._cpu0[1]:   # all threads of the process
            out["cpu_per_cycle_ms"] = 1e3 * (time.process_time() - self._cpu0[0]) / (self.loop.stats.cycles
                                                                                  - self._cpu0[1])
        out["publisher"] = self.publisher_mode
        if self._ring is not None:
            cost = self._ring.consumer_cpu_per_record
            out.update(samples_written=self._ring.written, samples_published=self._ring.taken,
                       samples_lost=self._ring.lost,
                       publisher_cpu_per_cycle_ms=None if cost is None else 1e3 * cost)
        return out

    def _end_publisher_process(self, timeout: float = 60.0) -> None:
        """Close the ring, let the publisher process publish what is left and end (SIGTERM after
        ``timeout`` s), keep its last figures, free the ring."""
        self._ring.close()
        child = self._child
        try:
            child.wait(timeout)
        except subprocess.TimeoutExpired:
            self.get_logger().error(f"the publisher process did not end in {timeout:g} s; "
                                    f"{self._ring.backlog} samples not published")
            child.terminate()
            child.wait(10.0)

    def shutdown(self) -> None:
        if self._thread is not None:
            self._queue.put(_STOP)
            self._thread.join(timeout=5.0)
        if self._child is not None:
            self._end_publisher_process()
        if self.loop is not None:
            self.loop.stop()
            if self.loop.start_wall is not None:       # the hardware started: there are figures
                print(json.dumps(self.summary()), flush=True)
            sys.stdout.flush()
        if self._ring is not None:
            self._ring.release()
            self._ring = None

