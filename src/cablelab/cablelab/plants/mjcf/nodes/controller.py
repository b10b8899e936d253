"""PD + model feedforward controller of any MuJoCo model: ``pd_feedforward --plant mjcf``.

On every ``joint_states`` message it computes the actuator controls of
:class:`..control.Feedforward` (computed torque from the description's model, with the latest
``payload_estimate``) for the reference and publishes them on ``effort_commands`` (model actuator
order), naming the stamp of the state it answers. The reference is the latest ``reference``
(``reference_source: topic``; a stale or missing one holds the first measured position) or a
built-in sine evaluated at the measurement stamp (``sine``, also published on ``reference``).
Bad messages (names, lengths, NaN) are rejected and counted on /diagnostics; nothing is
commanded from them.
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
from ..control import Feedforward, sine_reference
from ..topics import topic

PARAMETERS = (
    DESCRIPTION,
    Param("kp", 100.0, "proportional gain of the commanded acceleration", "1/s^2", ge=0.0, le=1e9),
    Param("kd", 20.0, "derivative gain of the commanded acceleration", "1/s", ge=0.0, le=1e9),
    Param("reference_source", "topic", "the reference: the reference topic or a built-in sine "
          "evaluated at the measurement stamp (sine)", choices=("topic", "sine")),
    Param("amplitude", 0.2, "amplitude of the built-in sine", "rad or m", ge=0.0, le=1e3),
    Param("frequency", 0.3, "frequency of the built-in sine", "Hz", gt=0.0, le=1e3),
    Param("reference_timeout", 0.5, "a reference older than this is stale", "s wall", gt=0.0),
)


#: largest payload (kg) and centre-of-mass distance from its body (m) the law takes
MAX_PAYLOAD, MAX_REACH = 1e4, 100.0


class MjcfController(PlantNode):
    def __init__(self):
        super().__init__("pd_feedforward")
        self.v = self.declare_params(PARAMETERS)
        self.law = None
        self.ref = None
        self.hold = None
        self.listen_for_description(self.v.description)
        self.start_diagnostics()

    def set_description(self, desc) -> None:
        sec = getattr(desc, "mjcf", None)
        if sec is None or self.law is not None:
            return
        super().set_description(desc)
        self.law = Feedforward(sec, desc.gravity, self.v.kp, self.v.kd)
        n = len(self.law.joints)
        self.inputs.add("joint_states", timeout=0.5, length=2 * n)
        self.inputs.add("reference", timeout=self.v.reference_timeout, length=3 * n,
                        required=self.v.reference_source == "topic")
        self.inputs.add("payload_estimate", timeout=60.0, length=4, required=False)
        self.pub = self.create_publisher(Float64MultiArray, topic(sec, "effort_commands"), publisher_qos())
        self.pub_ref = self.create_publisher(JointTrajectory, topic(sec, "reference"), publisher_qos())
        self.create_subscription(JointState, topic(sec, "joint_states"), self.on_state, stream_qos())
        if self.v.reference_source == "topic":
            self.create_subscription(JointTrajectory, topic(sec, "reference"), self.on_reference, stream_qos())
        if sec.payload_body:
            self.create_subscription(InertiaStamped, topic(sec, "payload_estimate"), self.on_payload,
                                     stream_qos())

    def on_reference(self, msg: JointTrajectory) -> None:
        _t, names, q, qd, qdd = convert.joint_trajectory_point(msg)
        n = len(self.law.joints)
        ok = list(names or ()) == self.law.joints and all(a is not None and a.size == n for a in (q, qd, qdd))
        vals = np.concatenate([q, qd, qdd]) if ok else None
        if self.inputs.accept("reference", vals, time.monotonic()):
            self.ref = (q, qd, qdd)

    def on_payload(self, msg: InertiaStamped) -> None:
        m, com = msg.inertia.m, np.array([msg.inertia.com.x, msg.inertia.com.y, msg.inertia.com.z])
        # a physical payload: a mass within MAX_PAYLOAD and a centre within MAX_REACH of its body
        ok = 0.0 <= m <= MAX_PAYLOAD and np.all(np.abs(com) <= MAX_REACH)
        if self.inputs.accept("payload_estimate", np.array([m, *com]) if ok else None, time.monotonic()):
            self.law.set_payload(m, com)

    def on_state(self, msg: JointState) -> None:
        t, names, q, qd, _eff = convert.joint_state_arrays(msg)
        n = len(self.law.joints)
        ok = names == self.law.joints and q is not None and qd is not None and q.size == n and qd.size == n
        if not self.inputs.accept("joint_states", np.concatenate([q, qd]) if ok else None, time.monotonic()):
            return
        if self.hold is None:
            self.hold = q.copy()
        if self.v.reference_source == "sine":
            dq, dqd, dqdd = sine_reference(t, n, self.v.amplitude, self.v.frequency)
            ref = (self.hold + dq, dqd, dqdd)
            self.pub_ref.publish(convert.joint_trajectory_msg(t, self.law.joints, *ref))
        elif self.ref is not None and self.inputs.fresh("reference", time.monotonic()):
            ref = self.ref
        else:                                   # no fresh reference: hold where it started
            ref = (self.hold, np.zeros(n), np.zeros(n))
        u = self.law.command(q, qd, *ref)
        self.pub.publish(convert.command_msg(u, stamp=t, label="joint"))


def make_node() -> PlantNode:
    return MjcfController()
