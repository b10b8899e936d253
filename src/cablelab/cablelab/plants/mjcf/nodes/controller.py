"""PD + model feedforward controller of any MuJoCo model: ``pd_feedforward --plant mjcf``.

On every ``joint_states`` message: the actuator controls of :class:`..control.Feedforward`
(computed torque from the description's model, with the latest ``payload_estimate``) for the
reference, on ``effort_commands`` (model actuator order) naming the state's stamp. The reference:
a bag of ``cablelab excite --plant mjcf`` (``reference_bag``) or a built-in sine around the first
measured position (``reference_source: sine``), played from the first state on and published on
``reference``; else the latest ``reference`` (stale or missing: hold the first measured position).
Bad messages (names, lengths, NaN) are rejected and counted on /diagnostics; nothing is commanded
from them. Parameters: :data:`.parameters.CONTROLLER`.
"""
from __future__ import annotations

import time

import numpy as np
from geometry_msgs.msg import InertiaStamped
from sensor_msgs.msg import JointState
from std_msgs.msg import Float64MultiArray
from trajectory_msgs.msg import JointTrajectory

from ....ros import convert
from ....ros.plant_node import PlantNode
from ....ros.qos import publisher_qos, stream_qos
from ..control import Feedforward, payload_values, sine_trajectory
from ..live import joint_values
from ..topics import topic
from .parameters import CONTROLLER as PARAMETERS


class MjcfController(PlantNode):
    def __init__(self):
        super().__init__("pd_feedforward")
        self.v = self.declare_params(PARAMETERS)
        self.law = self.player = self.ref = self.hold = None
        self.listen_for_description(self.v.description)
        self.start_diagnostics()

    def set_description(self, desc) -> None:
        sec, v = getattr(desc, "mjcf", None), self.v
        if sec is None or self.law is not None:
            return
        super().set_description(desc)
        self.law = Feedforward(sec, desc.gravity, v.kp, v.kd)
        self.joints, n, ref_topic = self.law.joints, len(self.law.joints), topic(sec, "reference")
        sine = sine_trajectory(n, v.amplitude, v.frequency) if v.reference_source == "sine" else None
        self.player = self.play_reference(v.reference_bag, ref_topic, self.joints, sine)
        self.inputs.add("joint_states", timeout=0.5, length=2 * n)
        self.inputs.add("reference", timeout=v.reference_timeout, length=3 * n, required=self.player is None)
        self.inputs.add("payload_estimate", timeout=60.0, length=4, required=False)
        self.pub = self.create_publisher(Float64MultiArray, topic(sec, "effort_commands"), publisher_qos())
        self.create_subscription(JointState, topic(sec, "joint_states"), self.on_state, stream_qos())
        if self.player is None:
            self.create_subscription(JointTrajectory, ref_topic, self.on_reference, stream_qos())
        if sec.payload_body:
            self.create_subscription(InertiaStamped, topic(sec, "payload_estimate"), self.on_payload, stream_qos())

    def on_reference(self, msg: JointTrajectory) -> None:
        ref = convert.reference_point(msg, self.joints)
        if self.accept("reference", None if ref is None else np.concatenate(ref)):
            self.ref = ref

    def on_payload(self, msg: InertiaStamped) -> None:
        _t, m, com = convert.inertia_arrays(msg)
        if self.accept("payload_estimate", vals := payload_values(m, com)):
            self.law.set_payload(vals[0], vals[1:])

    def on_state(self, msg: JointState) -> None:
        t, names, q, qd, _eff = convert.joint_state_arrays(msg)
        if not self.accept("joint_states", joint_values(names, self.joints, q, qd)):
            return
        if self.hold is None:                   # without a fresh reference: hold where it started
            self.hold = (q.copy(), np.zeros(q.size), np.zeros(q.size))
        fresh = self.ref is not None and self.inputs.fresh("reference", time.monotonic())
        ref = self.player(t, q) if self.player is not None else self.ref if fresh else self.hold
        self.pub.publish(convert.command_msg(self.law.command(q, qd, *ref), stamp=t, label="joint"))


def make_node() -> PlantNode:
    return MjcfController()
