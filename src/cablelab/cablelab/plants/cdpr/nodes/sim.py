"""CDPR simulator node: the MuJoCo CAROCA of 001 (:class:`cablelab.plants.cdpr.sim.CdprSim`: real
pulleys, friction winches) driven by ``/cdpr/effort_commands``.

Publishes the winch joint states, the cable tensions, the measured pose, the pick-and-place
reference of 001 sec. II-C, the ground truth, ``/clock`` and ``/plant_description`` (CONTRACT sec.
2; pre-serialised, :meth:`.outputs.CdprOutputs.simulator_sample`). When it steps and with which
torques (real time at ``rate`` Hz, or lock-step with the controller as fast as possible; without a
fresh command the winch brakes hold) is :class:`cablelab.plants.cdpr.stepping.SimStepper`; brakes
and slack cables are WARN on /diagnostics. Parameters: :data:`.parameters.SIM`.
"""
from __future__ import annotations

import time

from std_msgs.msg import Float64MultiArray

from ....description import load_description
from ....ros import rawmsg
from ....ros.plant_node import PlantNode
from ....ros.qos import stream_qos
from .. import topics
from ..markers import sim_markers
from ..sim import default_description_path
from ..stepping import SimStepper
from .outputs import CdprOutputs
from .parameters import SIM as PARAMETERS


class CdprSimNode(PlantNode):
    def __init__(self):
        super().__init__("cable_sim_node", start_parameter_services=False)  # smaller wait set
        v = self.declare_params(PARAMETERS)
        self.description = load_description(v.description or default_description_path())
        self.stepper = SimStepper.from_parameters(self.description, v, self.get_name(), self.mass_changed)
        self.sim, self.real_time = self.stepper.sim, v.real_time
        self.publish_pose, self.extras_every = v.publish_pose, v.extras_every
        self.start_gate()
        self.out = CdprOutputs(self, self.sim.n, truth=True)
        self.out.payload(self.sim.truth.total_mass, self.sim.truth.total_com)
        self.publish_description(self.description)
        if not self.real_time and v.rt_priority > 0:
            self.get_logger().warning("rt_priority ignored: lock-step mode runs as fast as possible")
        self.use_fast_executor()
        # real time: the commands wait queued (keep-last 1) until the step that applies them takes
        # the newest (one wake-up per step, the timer's); lock-step: a command wakes the node
        self.command_input(topics.EFFORT_COMMANDS, self.sim.n, v.command_timeout, stream_qos(1)
                           if self.real_time else stream_qos(), raw=True, polled=self.real_time)
        self.start_stepping(1.0 / v.rate if self.real_time else 0.0002, topics.MARKERS,
                            lambda: sim_markers(self.description, self.sim), lambda: self.sim.time,
                            v.markers_rate)
        # /diagnostics and the 3D view run right after a step, never just before the next one
        self.defer_timers(t for t in self.timers if t is not self.timer)

    @property
    def done(self) -> bool:
        return self.stepper.done

    def extend_status(self, level, msg, values):
        return self.stepper.report(level, msg, values)

    def on_command(self, msg: Float64MultiArray) -> None:
        """An effort command (serialised bytes, :func:`~cablelab.ros.rawmsg.command_arrays`)."""
        cmd = self.decode("effort_commands", rawmsg.command_arrays, msg)
        if cmd is not None and self.accept("effort_commands", cmd[0]):
            self.stepper.command(*cmd)

    def mass_changed(self, kg: float) -> None:
        self.out.payload(self.sim.truth.total_mass, self.sim.truth.total_com)
        self.get_logger().info(f"{kg:g} kg put on the platform at t = {self.sim.time:.3f} s")

    def tick(self) -> None:
        """Timer: the start gate, then :meth:`SimStepper.steps_due <cablelab.plants.cdpr.stepping.
        SimStepper.steps_due>` steps (real time: the first on time, the rest late), then a due
        deferred timer (/diagnostics or the 3D view)."""
        self.advance()
        self.run_deferred()

    def advance(self) -> None:
        if self.stepper.k == 0 and self.wait_subs:
            if self.waiting_for_subscribers(self.out.pub_js, self.stepper.last_publish, self.publish_state):
                return
            self.publish_state()
        self.take_polled(newest=True)      # the newest command (real time)
        for i in range(self.stepper.steps_due(time.monotonic())):
            self.step_once(late=i > 0)
            if self.done:
                return

    def step_once(self, late: bool = False) -> None:
        t0, now = time.perf_counter(), time.monotonic()
        if self.stepper.step(now, self.inputs.fresh("effort_commands", now), late):
            self.publish_state()
            self.latency.since(t0)

    def publish_state(self) -> None:
        self.out.simulator_sample(self.stepper, self.publish_pose, self.stepper.k % self.extras_every == 0)
        self.stepper.published(time.monotonic())


def make_node() -> PlantNode:
    return CdprSimNode()
