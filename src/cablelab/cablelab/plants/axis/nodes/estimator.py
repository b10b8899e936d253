"""Axis live parameter estimator node.

Recursive least squares (:class:`cablelab.rls.RecursiveLeastSquares`) of the axis inverse model
``u - m c g sin q = M qdd + Fv qd + Fc sign(qd) + offset`` (:func:`cablelab.plants.axis.control.
regressor`) from ``/axis/joint_states``; qdd and the mid-interval velocity come from consecutive
samples, the force from the later one (the simulator reports with each sample the command held
over the period ending there). A sample repeating the previous stamp is ignored. Publishes ``/axis/parameter_estimate``
(std_msgs/Float64MultiArray ``[M, Fv, Fc, offset]``, an addition to the contract, see
docs/nodes.md) every ``publish_every`` samples.

ROS parameters: :data:`PARAMETERS` (``payload_estimator --plant axis --help``).
"""
from __future__ import annotations


import numpy as np
from sensor_msgs.msg import JointState
from std_msgs.msg import Float64MultiArray

from .. import topics
from ..control import gravity_load, regressor
from ....rls import RecursiveLeastSquares
from ....ros import convert
from ....ros.plant_node import PlantNode
from ....ros.qos import catch_up_qos, publisher_qos
from .parameters import ESTIMATOR as PARAMETERS


class AxisEstimator(PlantNode):
    def __init__(self):
        super().__init__("payload_estimator")
        v = self.declare_params(PARAMETERS)
        self.rls = RecursiveLeastSquares(4, lam=v.forgetting, p0=1e4)
        self.every = v.publish_every
        self.eps = v.stiction_velocity
        self.gravity_moment, self.gravity = 0.0, 9.81
        self.prev = None  # (t, q, qd, effort)
        self.count = 0
        self.inputs.add("joint_states", timeout=0.5, length=2)
        self.pub = self.create_publisher(Float64MultiArray, topics.PARAMETER_ESTIMATE, publisher_qos())
        self.create_subscription(JointState, topics.JOINT_STATES, self.on_state, catch_up_qos())
        self.listen_for_description()
        self.start_diagnostics()

    def extend_status(self, level, msg, values):
        values.update({k: f"{v:.6g}" for k, v in zip(("M", "Fv", "Fc", "offset"), self.rls.theta)})
        values["samples"] = str(self.rls.n)
        return level, msg, values

    def set_description(self, desc) -> None:
        super().set_description(desc)
        if desc.axis is not None and desc.axis.joint_type == "revolute":
            self.gravity_moment, self.gravity = desc.axis.gravity_moment, desc.gravity

    def on_state(self, msg: JointState) -> None:
        t, _names, q, qd, eff = convert.joint_state_arrays(msg)
        one = q is not None and eff is not None and q.size == 1 and eff.size == 1
        both = np.concatenate([q, eff]) if one else None     # one position and one effort
        if not self.accept("joint_states", both):
            return
        if qd is None or qd.size != 1:
            qd = np.array([np.nan])
        cur = (t, float(q[0]), float(qd[0]), float(eff[0]))
        prev, self.prev = self.prev, cur
        if prev is None or not cur[0] > prev[0]:
            return
        dt = cur[0] - prev[0]
        v0 = prev[2] if np.isfinite(prev[2]) else (cur[1] - prev[1]) / dt
        v1 = cur[2] if np.isfinite(cur[2]) else (cur[1] - prev[1]) / dt
        # the effort reported with a sample is the command held over the period ending there
        y = cur[3] - gravity_load(0.5 * (prev[1] + cur[1]), self.gravity_moment, self.gravity)
        self.rls.update(regressor([0.5 * (v0 + v1)], [(v1 - v0) / dt], self.eps), [y])
        self.count += 1
        if self.count % self.every == 0:
            self.pub.publish(convert.float_array_msg(self.rls.theta))


def make_node() -> PlantNode:
    return AxisEstimator()
