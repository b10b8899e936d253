"""Axis live parameter estimator node: ``/axis/joint_states`` -> :class:`~..estimator.AxisRlsEstimator`
(recursive least squares of the axis inverse model) -> ``/axis/parameter_estimate``
(std_msgs/Float64MultiArray ``[M, Fv, Fc, offset]``, an addition to the contract, see
docs/nodes.md) every ``publish_every`` samples. Parameters: :data:`.parameters.ESTIMATOR`.
"""
from __future__ import annotations

import numpy as np
from sensor_msgs.msg import JointState
from std_msgs.msg import Float64MultiArray

from .. import topics
from ..estimator import NAMES, AxisRlsEstimator
from ....ros import convert
from ....ros.plant_node import PlantNode
from ....ros.qos import catch_up_qos, publisher_qos
from .parameters import ESTIMATOR as PARAMETERS


class AxisEstimator(PlantNode):
    def __init__(self):
        super().__init__("payload_estimator")
        v = self.declare_params(PARAMETERS)
        self.est = AxisRlsEstimator(v.forgetting, v.stiction_velocity)
        self.every, self.count = v.publish_every, 0
        self.inputs.add("joint_states", timeout=0.5, length=2)
        self.pub = self.create_publisher(Float64MultiArray, topics.PARAMETER_ESTIMATE, publisher_qos())
        self.create_subscription(JointState, topics.JOINT_STATES, self.on_state, catch_up_qos())
        self.listen_for_description()
        self.start_diagnostics()

    def extend_status(self, level, msg, values):
        values.update({k: f"{v:.6g}" for k, v in zip(NAMES, self.est.theta)})
        values["samples"] = str(self.est.rls.n)
        return level, msg, values

    def set_description(self, desc) -> None:
        super().set_description(desc)
        if desc.axis is not None and desc.axis.joint_type == "revolute":
            self.est.set_gravity(desc.axis.gravity_moment, desc.gravity)

    def on_state(self, msg: JointState) -> None:
        t, _names, q, qd, eff = convert.joint_state_arrays(msg)
        one = q is not None and eff is not None and q.size == 1 and eff.size == 1
        if not self.accept("joint_states", np.concatenate([q, eff]) if one else None):
            return                                           # (one position and one effort)
        qd = float(qd[0]) if qd is not None and qd.size == 1 else float("nan")
        if self.est.step(t, float(q[0]), qd, float(eff[0])):
            self.count += 1
            if self.count % self.every == 0:
                self.pub.publish(convert.float_array_msg(self.est.theta))


def make_node() -> PlantNode:
    return AxisEstimator()
