"""PD + model feedforward controller of any MuJoCo model: ``pd_feedforward --plant mjcf``.

On every ``joint_states`` message it computes the actuator controls of
:class:`..control.Feedforward` (computed torque from the description's model, with the latest
``payload_estimate``) for the reference and publishes them on ``effort_commands`` (model actuator
order), naming the stamp of the state it answers. The reference is a bag written by ``cablelab
excite --plant mjcf`` (``reference_bag``, played from the first state on and published on
``reference``), the latest ``reference`` (``reference_source: topic``; a stale or missing one
holds the first measured position) or a built-in sine around the first measured position
(``sine``, also published). Bad messages (names, lengths, NaN) are rejected and counted on
/diagnostics; nothing is commanded from them.
"""
from __future__ import annotations

import time

import numpy as np
from geometry_msgs.msg import InertiaStamped
from sensor_msgs.msg import JointState
from std_msgs.msg import Float64MultiArray
from trajectory_msgs.msg import JointTrajectory

from ....ros import convert
from ....ros.params import DESCRIPTION, Param
from ....ros.plant_node import PlantNode
from ....ros.qos import publisher_qos, stream_qos
from ....ros.reference import ReferencePlayer, reference_bag_param
from ..control import Feedforward, payload_values, sine_trajectory
from ..live import joint_values
from ..topics import TOPICS, topic

PARAMETERS = (
    DESCRIPTION,
    Param("kp", 100.0, "proportional gain of the commanded acceleration", "1/s^2", ge=0.0, le=1e9),
    Param("kd", 20.0, "derivative gain of the commanded acceleration", "1/s", ge=0.0, le=1e9),
    Param("reference_source", "topic", "the reference: the reference topic or a built-in sine "
          "around the first measured position (sine)", choices=("topic", "sine")),
    Param("amplitude", 0.2, "amplitude of the built-in sine", "rad or m", ge=0.0, le=1e3),
    Param("frequency", 0.3, "frequency of the built-in sine", "Hz", gt=0.0, le=1e3),
    Param("reference_timeout", 0.5, "a reference older than this is stale", "s wall", gt=0.0),
    reference_bag_param(TOPICS["reference"][0]),
)


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
        if v.reference_bag:
            self.player = ReferencePlayer.from_bag(self, v.reference_bag, ref_topic, self.joints)
        elif v.reference_source == "sine":
            self.player = ReferencePlayer(self, ref_topic, self.joints,
                                          sine_trajectory(n, v.amplitude, v.frequency))
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
        self.hold = (q.copy(), np.zeros(q.size), np.zeros(q.size)) if self.hold is None else self.hold
        if self.player is not None:
            ref = self.player(t, q)
        else:                                   # no fresh reference: hold where it started
            ref = self.ref if self.ref is not None and self.inputs.fresh("reference", time.monotonic()) \
                else self.hold
        self.pub.publish(convert.command_msg(self.law.command(q, qd, *ref), stamp=t, label="joint"))


def make_node() -> PlantNode:
    return MjcfController()
