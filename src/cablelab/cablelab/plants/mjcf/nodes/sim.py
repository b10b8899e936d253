"""Simulator node of any MuJoCo model: ``cable_sim_node --plant mjcf -p description:=FILE``.

Steps the description's model (:class:`..sim.MjcfSim`; without ``description`` the shipped
three-joint arm, ``plants/mjcf/examples/arm3.xml``) with the actuator controls of
``effort_commands`` (model actuator order; a stale or missing command: zero controls) and
publishes each period ``joint_states`` (every hinge/slide joint; effort = the actuators'
generalised force on it), ``cable_tensions`` (the ``tendons``), ``ground_truth/joint_states``,
``/clock``, ``/plant_description`` (the model inline) and, on a wall-clock timer, the 3D view
``markers`` (:mod:`..markers`); topic names as ``mjcf.topics`` says. Parameters: :data:`.parameters.SIM`.
"""
from __future__ import annotations

import math

from sensor_msgs.msg import JointState
from std_msgs.msg import Float64MultiArray

from ....description import load_description
from ....errors import CablelabError
from ....ros import convert
from ....ros.simulator import SimulatorNode
from ..description import section_of
from ..markers import sim_markers
from ..sim import MjcfSim, default_description, hidden_payload, publish_period
from ..topics import topic
from .parameters import SIM as PARAMETERS


class MjcfSimNode(SimulatorNode):
    def __init__(self):
        super().__init__()
        v = self.declare_params(PARAMETERS)
        self.description = load_description(v.description or default_description())
        sec = section_of(self.description)
        self.sim = MjcfSim(sec, self.description.gravity, hidden_payload(sec, v.payload_mass))
        self.ctrl = [0.0] * self.sim.model.nu
        self.start_gate()
        self.pub_js, self.pub_truth, self.pub_ten = self.state_publishers(
            (JointState, topic(sec, "joint_states")), (JointState, topic(sec, "ground_truth_joint_states")),
            (JointState, topic(sec, "cable_tensions") if sec.tendons else None))
        self.command_input(topic(sec, "effort_commands"), self.sim.model.nu, v.command_timeout)
        self.start_simulation(self.description, publish_period(self.sim.model.opt.timestep, v.rate),
                              topic(sec, "markers"), lambda: sim_markers(self.sim), v.markers_rate)

    def on_command(self, msg: Float64MultiArray) -> None:
        if (values := self.take_command("effort_commands", msg)) is not None:
            self.ctrl = [float(x) for x in values]

    def step(self, kind: str, fresh: bool) -> None:
        if not fresh:
            self.ctrl = [0.0] * self.sim.model.nu       # no (fresh) command: drives off
        self.sim.advance(self.ctrl, self.period)

    def publish_state(self) -> None:
        t, q, qd, effort, tension = self.sim.state()
        if not all(math.isfinite(x) for x in q):
            raise CablelabError("cable_sim_node --plant mjcf: the simulation diverged (NaN state)")
        self.clock.publish(t)
        for pub in (self.pub_js, self.pub_truth):
            pub.publish(convert.joint_state_msg(t, self.sim.joints, q, qd, effort))
        if self.pub_ten is not None:
            self.pub_ten.publish(convert.joint_state_msg(t, self.sim.tendons, None, None, tension))


def make_node() -> SimulatorNode:
    return MjcfSimNode()
