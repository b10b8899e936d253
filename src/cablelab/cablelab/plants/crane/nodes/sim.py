"""Crane simulator node: the MuJoCo boom crane of 002 (:class:`cablelab.plants.crane.sim.CraneSim`)
driven by ``/crane/effort_commands``.

Publishes (CONTRACT sec. 2) ``/crane/joint_states`` (slew, luff, hoist: position, velocity, effort
= applied command + sensor offset + noise), the motion-capture poses ``/crane/boom_tip_pose`` and
``/crane/payload_pose`` (noise, NaN dropouts), ``/crane/ground_truth/swing`` (theta1, theta2,
rope_length), ``/clock`` and ``/plant_description`` (transient-local).

``lockstep`` (default true): once commands flow, a state is followed by the command answering it
before the simulation advances (:class:`cablelab.ros.lockstep.LockStep` matches answers by stamp;
an answer is applied however late), so a slow controller slows the simulation down instead of
destabilising it; without an answer for ``lockstep_timeout`` s it runs in real time again until
commands flow. Without a fresh command the drives hold the crane (gravity compensation + damping,
like a brake: :func:`cablelab.plants.crane.control.sim_drive`), reported as WARN on /diagnostics.
Parameters: ``cable_sim_node --plant crane --help``.
"""
from __future__ import annotations

import os
import time

from geometry_msgs.msg import PoseStamped
from sensor_msgs.msg import JointState
from std_msgs.msg import Float64MultiArray

from ....description import load_description
from ....errors import CablelabError
from .. import topics
from ..control import sim_drive
from ..markers import state_markers
from ..model import JOINTS, CraneParams
from ....ros.clock import ClockPublisher
from ....ros.markers import start_markers
from ....ros import convert
from ....ros.lockstep import ADVANCE, LockStep
from ....ros.plant_node import PlantNode
from ....ros.inputs import ERROR
from ....ros.qos import publisher_qos, stream_qos
from ....ros.status import add_problem
from ..sim import CraneSim, truth_from_parameters
from .parameters import SIM as PARAMETERS

DEFAULT_DESCRIPTION = os.path.join(os.path.dirname(os.path.dirname(__file__)), "data", "crane.yaml")
SWING = ["theta1", "theta2", "rope_length"]


class CraneSimNode(PlantNode):
    def __init__(self):
        super().__init__("cable_sim_node")
        v = self.declare_params(PARAMETERS)
        self.description = load_description(v.description or DEFAULT_DESCRIPTION)
        if self.description.crane is None:
            raise CablelabError("cable_sim_node --plant crane: the description has no crane section")
        params = CraneParams.from_description(self.description, slew_inertia=v.slew_inertia,
                                              luff_inertia=v.luff_inertia)
        truth, q0 = truth_from_parameters(self.get_name(), params, v)
        self.rate = v.rate
        self.lock = LockStep(v.lockstep, wait_first=False, timeout=v.lockstep_timeout)
        self.start_gate()
        self.sim = CraneSim(truth, q0)
        self.u = None
        self.fallbacks = 0
        self.inputs.add("effort_commands", timeout=v.command_timeout, length=3)
        pub = lambda kind, topic: self.create_publisher(kind, topic, publisher_qos())  # noqa: E731
        self.pub_js = pub(JointState, topics.JOINT_STATES)
        self.pub_tip = pub(PoseStamped, topics.TIP_POSE)
        self.pub_pay = pub(PoseStamped, topics.PAYLOAD_POSE)
        self.pub_truth = pub(JointState, topics.SWING_TRUTH)
        self.clock = ClockPublisher(self)
        self.publish_description(self.description)
        self.create_subscription(Float64MultiArray, topics.EFFORT_COMMANDS, self.on_command, stream_qos())
        self.start_diagnostics()
        self.timer = self.create_timer(1.0 / self.rate, self.tick)
        start_markers(self, topics.MARKERS, lambda: state_markers(self.description, self.sim.state()[1]),
                      lambda: self.sim.state()[0], v.markers_rate)
        self.publish_state()

    def extend_status(self, level, msg, values):
        values["fallback (hold) steps"] = str(self.fallbacks)
        values["stale answers ignored (lock-step)"] = str(self.lock.stale_answers)
        values["simulation resets"] = str(self.sim.resets)
        if self.sim.resets:
            level, msg = add_problem(level, msg, ERROR, f"simulation diverged {self.sim.resets} times "
                                     "(restored at rest): commands too large?")
        return level, msg, values

    def on_command(self, msg: Float64MultiArray) -> None:
        values = self.take_command("effort_commands", msg, self.lock)
        if values is not None:
            self.u = values.copy()       # (never applied late; lock-step starts with the next)

    def tick(self) -> None:
        step = self.may_step(self.lock, self.pub_js, self.publish_state)
        if step is None:
            return  # wait for the controller's answer to the last state
        _, q, qd = self.sim.state()
        u, held = sim_drive(self.u, q, qd, self.sim.truth.params, answered=step == ADVANCE,
                            fresh=self.inputs.fresh("effort_commands", time.monotonic()),
                            lockstep=self.lock.enabled)
        self.fallbacks += held
        self.sim.advance(u, 1.0 / self.rate)
        self.publish_state()

    def publish_state(self) -> None:
        t, q, qd = self.sim.state()
        self.lock.published(t)
        m = self.sim.measurement()
        self.clock.publish(t)
        self.pub_js.publish(convert.joint_state_msg(t, JOINTS, m["joints"], m["joint_rates"], m["effort"]))
        self.pub_tip.publish(convert.pose_msg(t, m["tip"], m["tip_quat"]))
        self.pub_pay.publish(convert.pose_msg(t, m["payload"], m["payload_quat"]))
        self.pub_truth.publish(convert.joint_state_msg(t, SWING, [q[3], q[4], q[2]], [qd[3], qd[4], qd[2]]))


def make_node() -> PlantNode:
    return CraneSimNode()
