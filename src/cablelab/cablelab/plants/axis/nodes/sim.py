"""Axis simulator node: MuJoCo single axis (:mod:`cablelab.plants.axis.sim`) driven by
``/axis/effort_command``.

Publishes ``/axis/joint_states`` (name ``joint``: position, velocity, effort = applied command +
sensor offset; the command held over the period that ends at that state),
``/axis/ground_truth/joint_states`` (effort = true applied force), ``/clock`` and
``/plant_description`` (transient-local). ``lockstep``: the simulation advances one period only
after the command answering the last published state arrived, so a loaded machine slows the run
down instead of delaying the control loop (:class:`cablelab.ros.lockstep.LockStep`, ``wait_first``:
answers to earlier states are counted on /diagnostics and ignored).
Parameters: ``cable_sim_node --plant axis --help``.
"""
from __future__ import annotations

import time

from sensor_msgs.msg import JointState
from std_msgs.msg import Float64MultiArray

from .. import topics
from ....description import load_description
from ..sim import AxisSim, AxisTruth
from ....ros import convert
from ....ros.clock import ClockPublisher
from ....ros.lockstep import FREE, LockStep
from ....ros.markers import start_markers
from ....ros.plant_node import PlantNode
from ....ros.qos import publisher_qos, stream_qos
from .parameters import SIM as PARAMETERS

DEFAULT_DESCRIPTION = ("plant: axis\nname: simulated linear axis\ngravity: 9.81\n"
                       "axis:\n  joint_type: prismatic\n  inertia: 2.0\n")


class AxisSimNode(PlantNode):
    def __init__(self):
        super().__init__("cable_sim_node")
        v = self.declare_params(PARAMETERS)
        self.description = load_description(v.description or DEFAULT_DESCRIPTION)
        nominal = self.description.axis.inertia if self.description.axis else None
        inertia = v.inertia if v.inertia == v.inertia else float(nominal or 2.0)
        truth = AxisTruth(inertia=inertia, viscous=v.viscous, coulomb=v.coulomb, offset=v.offset,
                          timestep=v.timestep)
        self.rate = v.rate
        self.resend = v.lockstep_resend
        self.lock = LockStep(v.lockstep, wait_first=True, resend=self.resend)
        self.start_gate()
        self.sim = AxisSim(self.description, truth)
        self.u = 0.0
        self.inputs.add("effort_command", timeout=v.command_timeout, length=1)

        self.pub_js = self.create_publisher(JointState, topics.JOINT_STATES, publisher_qos())
        self.pub_truth = self.create_publisher(JointState, topics.GROUND_TRUTH, publisher_qos())
        self.clock = ClockPublisher(self)
        self.publish_description(self.description)
        self.create_subscription(Float64MultiArray, topics.EFFORT_COMMAND, self.on_command, stream_qos())
        self.start_diagnostics()
        self.timer = self.create_timer(1.0 / self.rate, self.tick)
        from ..markers import axis_markers

        start_markers(self, "/axis/markers", lambda: axis_markers(self.description, self.sim.state()[1], truth.inertia),
                      lambda: self.sim.t, v.markers_rate)
        self.publish_state()

    def extend_status(self, level, msg, values):
        values["sim time s"] = f"{self.sim.t:.3f}"
        values["stale answers ignored (lock-step)"] = str(self.lock.stale_answers)
        return level, msg, values

    def on_command(self, msg: Float64MultiArray) -> None:
        values = self.take_command("effort_command", msg, self.lock)
        if values is not None:
            self.u = float(values[0])

    def tick(self) -> None:
        step = self.may_step(self.lock, self.pub_js, self.publish_state, self.resend)
        if step is None:
            return
        if step == FREE and not self.inputs.fresh("effort_command", time.monotonic()):
            self.u = 0.0  # no (fresh) command: the drive is switched off
        self.sim.advance(self.u, 1.0 / self.rate)
        self.publish_state()

    def publish_state(self) -> None:
        t, q, qd = self.sim.state()
        self.lock.published(t)
        self.clock.publish(t)
        self.pub_js.publish(convert.joint_state_msg(t, ["joint"], [q], [qd], [self.sim.measured_effort(self.u)]))
        self.pub_truth.publish(convert.joint_state_msg(t, ["joint"], [q], [qd], [self.u]))


def make_node() -> PlantNode:
    return AxisSimNode()
