"""Axis PD + feedforward controller node.

On every ``/axis/joint_states`` message (event-driven, in the measurement's own time base) it
publishes ``u = M_ff qdd_ref + Kp (q_ref - q) + Kd (qd_ref - qd)``
(:func:`cablelab.plants.axis.control.pd_feedforward`) on ``/axis/effort_command``, naming the
stamp of the state it answers (:func:`cablelab.ros.convert.command_msg`: a lock-step simulator
applies only the answer to its latest state). The reference is the latest ``/axis/reference``
(``reference_source: topic``, default), a built-in sine evaluated at the measurement stamp
(``reference_source: sine``) or a ``reference_bag`` written by ``cablelab excite`` (played from
the first state on); the last two are published on ``/axis/reference`` so recordings hold them.
Parameters: ``pd_feedforward --plant axis --help``.
"""
from __future__ import annotations

import time

import numpy as np
from sensor_msgs.msg import JointState
from std_msgs.msg import Float64MultiArray
from trajectory_msgs.msg import JointTrajectory

from .. import topics
from ..control import pd_feedforward, sine_reference
from ....ros import convert
from ....ros.plant_node import PlantNode
from ....ros.qos import publisher_qos, stream_qos
from ....ros.reference import ReferencePlayer
from .parameters import CONTROLLER as PARAMETERS


class AxisController(PlantNode):
    def __init__(self):
        super().__init__("pd_feedforward")
        v = self.declare_params(PARAMETERS)
        self.kp = v.kp
        self.kd = v.kd
        self.inertia_param = v.inertia
        self.inertia = 0.0 if np.isnan(self.inertia_param) else self.inertia_param
        self.source = v.reference_source
        self.amplitude = v.amplitude
        self.frequency = v.frequency
        self.offset = v.offset
        self.player = None
        if v.reference_bag:
            self.player = ReferencePlayer.from_bag(self, v.reference_bag, topics.REFERENCE, ["joint"])
            self.source = "bag"
        self.ref = None  # (q, qd, qdd) from the topic
        self.inputs.add("joint_states", timeout=0.5, length=1)
        self.inputs.add("reference", timeout=v.reference_timeout, length=1,
                        required=self.source == "topic")

        self.pub_cmd = self.create_publisher(Float64MultiArray, topics.EFFORT_COMMAND, publisher_qos())
        self.pub_ref = self.create_publisher(JointTrajectory, topics.REFERENCE, publisher_qos()) \
            if self.source == "sine" else None
        self.create_subscription(JointState, topics.JOINT_STATES, self.on_state, stream_qos())
        if self.source == "topic":
            self.create_subscription(JointTrajectory, topics.REFERENCE, self.on_reference, stream_qos())
        self.listen_for_description()
        self.start_diagnostics()

    def extend_status(self, level, msg, values):
        values["feedforward inertia"] = f"{self.inertia:g}"
        return level, msg, values

    def set_description(self, desc) -> None:
        super().set_description(desc)
        if np.isnan(self.inertia_param) and desc.axis is not None and desc.axis.inertia:
            self.inertia = float(desc.axis.inertia)

    def on_reference(self, msg: JointTrajectory) -> None:
        ref = convert.reference_point(msg)
        if self.accept("reference", None if ref is None else ref[0]):
            self.ref = tuple(float(x[0]) for x in ref)

    def on_state(self, msg: JointState) -> None:
        t, _names, q, qd, _eff = convert.joint_state_arrays(msg)
        now = time.monotonic()
        if not self.accept("joint_states", q):
            return
        if qd is None or qd.size != q.size or not np.isfinite(qd).all():
            qd = np.zeros_like(q)
        if self.player is not None:
            q_ref, qd_ref, qdd_ref = (float(x[0]) for x in self.player(t, q))
        elif self.source == "sine":
            q_ref, qd_ref, qdd_ref = (float(v) for v in sine_reference(t, self.amplitude, self.frequency,
                                                                        self.offset))
            self.pub_ref.publish(convert.joint_trajectory_msg(t, ["joint"], [q_ref], [qd_ref], [qdd_ref]))
        elif self.ref is not None and self.inputs.fresh("reference", now):
            q_ref, qd_ref, qdd_ref = self.ref
        else:
            return  # no reference: command nothing, the simulator's command timeout stops the drive
        u = pd_feedforward(q[0], qd[0], q_ref, qd_ref, qdd_ref, self.kp, self.kd, self.inertia)
        self.pub_cmd.publish(convert.command_msg([u], stamp=t, label="joint"))


def make_node() -> PlantNode:
    return AxisController()
