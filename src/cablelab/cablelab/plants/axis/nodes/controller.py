"""Axis PD + feedforward controller node.

On every ``/axis/joint_states`` message (event-driven, in the measurement's own time base) it
publishes ``u = M_ff qdd_ref + Kp (q_ref - q) + Kd (qd_ref - qd)``
(:func:`cablelab.plants.axis.control.pd_feedforward`) on ``/axis/effort_command``, naming the
stamp of the state it answers (:func:`cablelab.ros.convert.command_msg`: a lock-step simulator
applies only the answer to its latest state). The reference is the latest ``/axis/reference``
(``reference_source: topic``, default), a built-in sine evaluated at the measurement stamp
(``reference_source: sine``) or a ``reference_bag`` written by ``cablelab excite`` (played from
the first state on); the last two are published on ``/axis/reference`` so recordings hold them
(:class:`cablelab.ros.reference.FollowedReference`). Parameters: :data:`.parameters.CONTROLLER`.
"""
from __future__ import annotations

import numpy as np
from sensor_msgs.msg import JointState
from std_msgs.msg import Float64MultiArray

from .. import topics
from ..control import pd_feedforward, sine_trajectory
from ....ros import convert
from ....ros.plant_node import PlantNode
from ....ros.qos import publisher_qos, stream_qos
from ....ros.reference import FollowedReference
from .parameters import CONTROLLER as PARAMETERS


class AxisController(PlantNode):
    def __init__(self):
        super().__init__("pd_feedforward")
        v = self.declare_params(PARAMETERS)
        self.kp, self.kd, self.inertia_param = v.kp, v.kd, v.inertia
        self.inertia = 0.0 if np.isnan(v.inertia) else v.inertia
        sine = sine_trajectory(v.amplitude, v.frequency, v.offset) if v.reference_source == "sine" else None
        self.reference = FollowedReference(self, topics.REFERENCE, ["joint"], v.reference_bag, sine,
                                           v.reference_timeout, absolute=True, any_names=True)
        self.inputs.add("joint_states", timeout=0.5, length=1)
        self.pub_cmd = self.create_publisher(Float64MultiArray, topics.EFFORT_COMMAND, publisher_qos())
        self.create_subscription(JointState, topics.JOINT_STATES, self.on_state, stream_qos())
        self.listen_for_description()
        self.start_diagnostics()

    def extend_status(self, level, msg, values):
        values["feedforward inertia"] = f"{self.inertia:g}"
        return level, msg, values

    def set_description(self, desc) -> None:
        super().set_description(desc)
        if np.isnan(self.inertia_param) and desc.axis is not None and desc.axis.inertia:
            self.inertia = float(desc.axis.inertia)

    def on_state(self, msg: JointState) -> None:
        t, _names, q, qd, _eff = convert.joint_state_arrays(msg)
        if not self.accept("joint_states", q):
            return
        if qd is None or qd.size != q.size or not np.isfinite(qd).all():
            qd = np.zeros_like(q)
        ref = self.reference(t, q)
        if ref is None:
            return  # no reference: command nothing, the simulator's command timeout stops the drive
        q_ref, qd_ref, qdd_ref = (float(np.ravel(x)[0]) for x in ref)
        u = pd_feedforward(q[0], qd[0], q_ref, qd_ref, qdd_ref, self.kp, self.kd, self.inertia)
        self.pub_cmd.publish(convert.command_msg([u], stamp=t, label="joint"))


def make_node() -> PlantNode:
    return AxisController()
