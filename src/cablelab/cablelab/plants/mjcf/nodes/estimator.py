"""Live payload estimator of any MuJoCo model: ``payload_estimator --plant mjcf``.

Takes the machine from ``/plant_description`` (or ``-p description:=FILE``), then listens to
its ``joint_states`` (names as in the model, remapping of ``mjcf.topics`` honoured) and, when the
description names measured ``tendons``, to ``cable_tensions``; every ``publish_every`` joint
states it fits the payload on ``mjcf.payload_body`` over the last ``window`` seconds
(:class:`..live.PayloadWindow`: tensions paired with the joint states by stamp, MuJoCo's inverse
dynamics and its payload columns) and publishes ``payload_estimate``
(geometry_msgs/InertiaStamped: ``m``, ``com`` in the payload body's frame). A message whose
names, lengths or values do not fit the model is rejected and counted on /diagnostics.
Parameters: :data:`.parameters.ESTIMATOR`.
"""
from __future__ import annotations

from geometry_msgs.msg import InertiaStamped
from sensor_msgs.msg import JointState

from ....ros import convert
from ....ros.plant_node import PlantNode
from ....ros.qos import catch_up_qos, publisher_qos
from ..live import PayloadWindow
from ..topics import topic
from .parameters import ESTIMATOR as PARAMETERS


class MjcfEstimator(PlantNode):
    def __init__(self):
        super().__init__("payload_estimator")
        self.v = self.declare_params(PARAMETERS)
        self.win: PayloadWindow | None = None
        self.listen_for_description(self.v.description)
        self.start_diagnostics()

    def set_description(self, desc) -> None:
        sec = getattr(desc, "mjcf", None)
        if sec is None or not sec.payload_body:
            self.description_problem = "the description names no mjcf.payload_body"
            return
        if self.win is not None:
            return
        super().set_description(desc)
        self.win = w = PayloadWindow(desc, self.v.window, self.v.publish_every)
        self.inputs.add("joint_states", timeout=0.5, length=2 * len(w.joints))
        self.pub = self.create_publisher(InertiaStamped, topic(sec, "payload_estimate"), publisher_qos())
        self.create_subscription(JointState, topic(sec, "joint_states"), self.on_state, catch_up_qos())
        if w.tendons:
            self.inputs.add("cable_tensions", timeout=0.5, length=len(w.tendons))
            self.create_subscription(JointState, topic(sec, "cable_tensions"), self.on_tension, catch_up_qos())

    def extend_status(self, level, msg, values):
        return (level, msg, values) if self.win is None else self.win.report(level, msg, values)

    def on_tension(self, msg: JointState) -> None:
        if self.win is None or not self.win.tendons:        # not subscribed: nothing measured
            return
        t, names, _q, _qd, eff = convert.joint_state_arrays(msg)
        if self.accept("cable_tensions", ten := self.win.tension_values(names, eff)):
            self.win.tension(t, ten)

    def on_state(self, msg: JointState) -> None:
        t, names, q, _qd, eff = convert.joint_state_arrays(msg)
        if not self.accept("joint_states", values := self.win.state_values(names, q, eff)):
            return
        if (est := self.win.state(t, q, values[q.size:])) is not None:
            sec = self.description.mjcf
            self.pub.publish(convert.inertia_msg(self.win.last_t, est.m, est.com, frame_id=sec.payload_body))


def make_node() -> PlantNode:
    return MjcfEstimator()
