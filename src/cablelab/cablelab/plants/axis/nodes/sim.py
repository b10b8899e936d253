"""Axis simulator node: MuJoCo single axis (:mod:`cablelab.plants.axis.sim`) driven by
``/axis/effort_command``.

Publishes ``/axis/joint_states`` (name ``joint``: position, velocity, effort = applied command +
sensor offset; the command held over the period that ends at that state),
``/axis/ground_truth/joint_states`` (effort = true applied force), ``/clock`` and
``/plant_description`` (transient-local). ``lockstep``: the simulation advances one period only
after the command answering the last published state arrived, so a loaded machine slows the run
down instead of delaying the control loop (:class:`cablelab.ros.lockstep.LockStep`, ``wait_first``:
answers to earlier states are counted on /diagnostics and ignored). Parameters: :data:`.parameters.SIM`.
"""
from __future__ import annotations

from sensor_msgs.msg import JointState
from std_msgs.msg import Float64MultiArray

from .. import topics
from ..markers import axis_markers
from ..sim import DEFAULT_DESCRIPTION, AxisSim, truth_from_parameters
from ....description import load_description
from ....ros import convert
from ....ros.lockstep import LockStep
from ....ros.qos import stream_qos
from ....ros.simulator import FREE, SimulatorNode
from .parameters import SIM as PARAMETERS


class AxisSimNode(SimulatorNode):
    command = "effort_command"

    def __init__(self):
        super().__init__()
        v = self.declare_params(PARAMETERS)
        desc = load_description(v.description or DEFAULT_DESCRIPTION)
        self.sim = AxisSim(desc, truth_from_parameters(desc, v))
        self.rate, self.republish_every, self.u = v.rate, v.lockstep_resend, 0.0
        self.lock = LockStep(v.lockstep, wait_first=True, resend=v.lockstep_resend)
        self.start_gate()
        self.inputs.add("effort_command", timeout=v.command_timeout, length=1)
        self.pub_js, self.pub_truth = self.state_publishers((JointState, topics.JOINT_STATES),
                                                            (JointState, topics.GROUND_TRUTH))
        self.create_subscription(Float64MultiArray, topics.EFFORT_COMMAND, self.on_command, stream_qos())
        self.start_simulation(desc, 1.0 / self.rate, topics.MARKERS, lambda: axis_markers(
            desc, self.sim.state()[1], self.sim.truth.inertia), v.markers_rate)

    def on_command(self, msg: Float64MultiArray) -> None:
        values = self.take_command("effort_command", msg, self.lock)
        if values is not None:
            self.u = float(values[0])

    def step(self, kind: str, fresh: bool) -> None:
        if kind == FREE and not fresh:
            self.u = 0.0  # no (fresh) command: the drive is switched off
        self.sim.advance(self.u, 1.0 / self.rate)

    def publish_state(self) -> None:
        t, q, qd = self.sim.state()
        self.lock.published(t)
        self.clock.publish(t)
        self.pub_js.publish(convert.joint_state_msg(t, ["joint"], [q], [qd], [self.sim.measured_effort(self.u)]))
        self.pub_truth.publish(convert.joint_state_msg(t, ["joint"], [q], [qd], [self.u]))


def make_node() -> SimulatorNode:
    return AxisSimNode()
