"""CDPR simulator node: the MuJoCo CAROCA of 001 (:class:`cablelab.plants.cdpr.sim.CdprSim`: real
pulleys, friction winches) driven by ``/cdpr/effort_commands``.

Publishes the winch joint states, the cable tensions, the measured pose, the pick-and-place
reference of 001 sec. II-C, the ground truth, ``/clock`` and ``/plant_description`` (CONTRACT sec.
2; pre-serialised, :class:`.outputs.CdprOutputs`). When it steps and with which torques (real time
at ``rate`` Hz, or lock-step with the controller as fast as possible; without a fresh command the
winch brakes hold) is :class:`cablelab.plants.cdpr.stepping.SimStepper`; brakes and slack cables
are WARN on /diagnostics. Parameters: :data:`.parameters.SIM`.

Real time, a deadline publishes the joint states and little else: a command that answers the last
state wakes the node, which computes the step it drives at once (``SimStepper.step_ahead``), then
publishes the rest of the last sample (tensions, reference, /clock, pose, truth) and runs a due
/diagnostics or 3D view, while the controller works on its next terms; without such an answer the
deadline steps with the last command as before and publishes everything.

Real time with the compiled path (:mod:`cablelab.plants.cdpr.sim_path`, used when
:mod:`cablelab.native` can build it and ``CABLELAB_NATIVE`` is not ``0``): a C thread runs that
law on the deadlines, takes the commands and publishes the joint states, the tensions and the
reference; the node drains its samples every few periods and publishes the rest from them.
Lock-step runs in Python.
"""
from __future__ import annotations

import atexit
import time

import numpy as np
from std_msgs.msg import Float64MultiArray

from .... import native
from ....description import load_description
from ....ros import rawmsg
from ....ros.fastspin import yield_to_compiled
from ....ros.plant_node import FINISH_ACK_TIMEOUT, PlantNode
from ....ros.qos import stream_qos
from .. import topics
from ..markers import sim_markers
from ..sim import default_description_path
from ..sim_path import CompiledSimPath, library
from ..stepping import SimStepper
from .outputs import CdprOutputs
from .parameters import SIM as PARAMETERS

DRAIN_PERIOD = 0.01     # s wall: the compiled path's samples are drained (the extras published) this often


class CdprSimNode(PlantNode):
    def __init__(self):
        super().__init__("cable_sim_node", start_parameter_services=False)  # smaller wait set
        v = self.declare_params(PARAMETERS)
        self.description = load_description(v.description or default_description_path())
        self.stepper = SimStepper.from_parameters(self.description, v, self.get_name(), self.mass_changed)
        self.sim, self.real_time = self.stepper.sim, v.real_time
        self.publish_pose, self.extras_every = v.publish_pose, v.extras_every
        self.start_gate()
        self.compiled = self.compiled_path(v) if self.real_time else None
        self.out = CdprOutputs(self, self.sim.n, truth=True, state=self.compiled is None)
        if self.compiled is not None:
            try:
                self.compiled.connect(self.out, topics.JOINT_STATES, topics.CABLE_TENSIONS, topics.REFERENCE,
                                      topics.EFFORT_COMMANDS, self.context.get_domain_id())
                atexit.register(self.compiled.close)     # the thread stops before the interpreter
            except ValueError as exc:
                self.get_logger().warning(f"the Python per-period path: the compiled one could not start ({exc})")
                self.compiled.close()
                self.compiled = None
                self.out.state_publishers(self)
        self.path = "compiled" if self.compiled is not None else "Python"
        self.last_row = None        # compiled path: the last sample drained, not yet mirrored
        self.out.payload(self.sim.truth.total_mass, self.sim.truth.total_com)
        self.publish_description(self.description)
        if not self.real_time and v.rt_priority > 0:
            self.get_logger().warning("rt_priority ignored: lock-step mode runs as fast as possible")
        self.use_fast_executor()
        self.ready = None           # (joint state bytes, rest, s of work) of a step computed ahead
        self.rest = None            # the rest of the last published sample, still to publish
        # a command wakes the node (keep-last 1: the newest; the fast executor takes it before a
        # deadline of the same wake-up)
        if self.compiled is not None:       # the C thread takes them; counted here from its counts
            self.inputs.add("effort_commands", timeout=v.command_timeout, length=self.sim.n)
            period = max(1.0 / v.rate, DRAIN_PERIOD)
        else:
            self.command_input(topics.EFFORT_COMMANDS, self.sim.n, v.command_timeout,
                               stream_qos(1) if self.real_time else stream_qos(), raw=True)
            period = 1.0 / v.rate if self.real_time else 0.0002
        self.start_stepping(period, topics.MARKERS,
                            lambda: sim_markers(self.description, self.mirrored()), lambda: self.mirrored().time,
                            v.markers_rate)
        # /diagnostics and the 3D view run after a step or an answer, never just before a deadline
        self.defer_timers(t for t in self.timers if t is not self.timer)

    def compiled_path(self, v) -> CompiledSimPath | None:
        """The compiled per-period path over the stepper, or None (logged: why not)."""
        lib = library()
        if lib is None:
            self.get_logger().info(f"the Python per-period path: {native.unavailable_reason('sim_path')}")
            return None
        try:
            return CompiledSimPath(lib, self.stepper, v.command_timeout)
        except ValueError as exc:
            self.get_logger().warning(f"the Python per-period path: {exc}")
            return None

    @property
    def done(self) -> bool:
        return self.stepper.done and not self.stepper.ahead

    def status(self):
        if self.compiled is not None:
            self.compiled.update(self.inputs)    # the C thread's counts, now
            self.mirrored()
        return super().status()

    def mirrored(self):
        """The simulation (compiled path: its mirror brought to the last drained sample)."""
        if self.last_row is not None:
            self.compiled.mirror(self.last_row)
            self.last_row = None
        return self.sim

    def extend_status(self, level, msg, values):
        values["per-period path"] = self.path
        if self.compiled is not None:
            c = self.compiled.counts
            if c["ring_lost"]:
                values["samples not published (drained too late)"] = str(c["ring_lost"])
            values.update({"publishes over 0.2 ms (joint states/tensions/reference)":
                           f"{c['slow_joint_states']}/{c['slow_tensions']}/{c['slow_reference']}",
                           "slowest publish ms": f"{c['publish_max_ns'] * 1e-6:.3f}",
                           "latest wake-up ms": f"{c['wake_max_ns'] * 1e-6:.3f}"})
        return self.stepper.report(level, msg, values)

    def all_acknowledged(self) -> bool:
        return super().all_acknowledged() and (self.compiled is None or self.compiled.all_acked())

    def drain(self, executor, timeout: float = FINISH_ACK_TIMEOUT) -> None:
        super().drain(executor, timeout)
        if self.compiled is not None and self.done and not self.compiled.all_acked(timeout):
            self.get_logger().warning(f"exiting with joint states not acknowledged after {timeout:g} s")

    def destroy_node(self):
        if self.compiled is not None:
            self.compiled.close()
        return super().destroy_node()

    def follow(self) -> None:
        """Compiled path: the start gate, then the C thread started; the samples it published
        since the last call, each one's rest published from the mirror."""
        c = self.compiled
        if not c.started:
            if self.wait_subs:
                if self.waiting_for_subscribers(c, self.stepper.last_publish, self.publish_state):
                    return
                self.publish_state()
            c.start()
            self.get_logger().info(f"compiled path started: {yield_to_compiled(idle=self.python_idle)}")
        c.update(self.inputs)       # (before the drain: a sample the counts know of is in the ring)
        rows = c.drain()
        for work in rows[:, 2]:
            self.latency.add(float(work))
        extras = rows[:, 1].astype(np.int64) % self.extras_every == 0
        for row in rows[extras | (rows[:, 3] > c.mass_seen)]:
            t, k, work, put_on = c.mirror(row)
            if put_on:
                self.stepper.put_on_mass(model=False)
            if k % self.extras_every == 0:
                self.out.extras(t, *self.extras_of())
        # the last sample, mirrored when the 3D view or /diagnostics read it (mirrored())
        self.last_row = None if not len(rows) or extras[-1] else rows[-1].copy()

    def on_command(self, msg: Float64MultiArray) -> None:
        """An effort command (serialised bytes, :func:`~cablelab.ros.rawmsg.command_arrays`); in
        real time, the answer to the last state computes the step it drives now, then the rest of
        the last sample goes out."""
        cmd = self.decode("effort_commands", rawmsg.command_arrays, msg)
        if cmd is not None and self.accept("effort_commands", cmd[0]):
            self.stepper.command(*cmd)
            if self.real_time and not (self.wait_subs and self.stepper.k == 0):
                self.step_ahead()
        if self.real_time and self.rest is not None:
            self.publish_rest()
            if self.stepper.time_left(time.monotonic()) * self.stepper.rate > 0.5:
                self.run_deferred()

    def mass_changed(self, kg: float) -> None:
        self.out.payload(self.sim.truth.total_mass, self.sim.truth.total_com)
        self.get_logger().info(f"{kg:g} kg put on the platform at t = {self.sim.time:.3f} s")

    def tick(self) -> None:
        """Timer: the start gate, then :meth:`SimStepper.steps_due <cablelab.plants.cdpr.stepping.
        SimStepper.steps_due>` states published (real time: the first on time, the rest late; the
        first one computed ahead if its answer came), then, unless the rest of the sample waits
        for the answer, a due deferred timer (/diagnostics or the 3D view). Compiled path:
        :meth:`follow`."""
        if self.compiled is not None:
            self.follow()
            self.run_deferred()
            return
        self.advance()
        if self.done and self.rest is not None:
            self.publish_rest()         # the last sample's rest: no answer is coming
        if self.rest is None:
            self.run_deferred()

    def advance(self) -> None:
        if self.stepper.k == 0 and self.wait_subs:
            if self.waiting_for_subscribers(self.out.pub_js, self.stepper.last_publish, self.publish_state):
                return
            self.publish_state()
        for i in range(self.stepper.steps_due(time.monotonic())):
            if self.stepper.ahead:
                self.publish_ready()
            else:
                self.step_once(late=i > 0)
            if self.done:
                return

    def step_once(self, late: bool = False) -> None:
        """The step due now, with the last command (or the brakes), and its whole sample."""
        t0, now = time.perf_counter(), time.monotonic()
        if self.stepper.step(now, self.inputs.fresh("effort_commands", now), late):
            self.ready = (*self.out.state_sample(self.stepper, self.publish_pose, self.extras()), 0.0)
            self.publish_ready(t0)

    def step_ahead(self) -> None:
        """The step the answer to the last state drives, computed now; its state waits for its
        deadline (:meth:`publish_ready`)."""
        t0 = time.perf_counter()
        if self.stepper.step_ahead(time.monotonic()):
            joints, rest = self.out.state_sample(self.stepper, self.publish_pose, self.extras())
            self.ready = (joints, rest, time.perf_counter() - t0)

    def publish_ready(self, t0: float | None = None) -> None:
        """Publish the joint states of the step computed last (its deadline came), then the rest
        of the sample before it if still unpublished; the rest of this one waits for the answer
        when the step was computed ahead (the controller keeps up), else goes out now. The
        latency is the step's work: computing it and publishing its state."""
        t1 = time.perf_counter() if t0 is None else t0
        joints, rest, work = self.ready
        ahead = self.stepper.ahead
        self.ready = None
        self.out.pub_js.publish(joints)
        self.stepper.published(time.monotonic())
        self.latency.add(work + time.perf_counter() - t1)
        if self.rest is not None:
            self.publish_rest()
        self.rest = rest
        if not ahead:
            self.publish_rest()

    def publish_rest(self) -> None:
        rest, self.rest = self.rest, None
        self.out.rest_sample(rest)

    def extras(self) -> bool:
        return self.stepper.k % self.extras_every == 0

    def extras_of(self) -> tuple:
        """(measured pose or None, true pose) of the sample the simulation holds now
        (:meth:`CdprOutputs.extras <.outputs.CdprOutputs.extras>`)."""
        ms = self.sim.measure()
        return (ms["position"], ms["quat"]) if self.publish_pose else None, self.sim.truth_pose()

    def publish_state(self) -> None:
        """The whole sample of the present sim time, now (the start and the start gate's probe)."""
        if self.compiled is not None:
            self.compiled.publish_now()
            if self.extras():
                self.out.extras(self.sim.time, *self.extras_of())
        else:
            self.out.simulator_sample(self.stepper, self.publish_pose, self.extras())
        self.stepper.published(time.monotonic())


def make_node() -> PlantNode:
    return CdprSimNode()
