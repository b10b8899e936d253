"""``payload_estimator --plant pendulum``: recursive least squares of the nominal model
``tau = I qdd`` from ``/pendulum/joint_states`` (qdd from consecutive velocities, the torque held over
the period), published as ``/pendulum/parameter_estimate`` ``[I]`` every ``publish_every`` samples.
ROS parameters: :data:`PARAMETERS`.
"""
from __future__ import annotations

import time

from sensor_msgs.msg import JointState
from std_msgs.msg import Float64MultiArray

from cablelab.rls import RecursiveLeastSquares
from cablelab.ros import convert
from cablelab.ros.params import Param
from cablelab.ros.plant_node import PlantNode
from cablelab.ros.qos import catch_up_qos, publisher_qos

from .. import topics

PARAMETERS = (
    Param("forgetting", 1.0, "forgetting factor of the recursive least squares (1 = none)", gt=0.0, le=1.0),
    Param("publish_every", 20, "publish the estimate every this many samples", ge=1, le=10 ** 9),
)


class PendulumEstimator(PlantNode):
    def __init__(self):
        super().__init__("payload_estimator")
        v = self.declare_params(PARAMETERS)
        self.rls = RecursiveLeastSquares(1, lam=v.forgetting, p0=1e4)
        self.every = v.publish_every
        self.prev = None     # (t, qd)
        self.inputs.add("joint_states", timeout=0.5, length=1)
        self.pub = self.create_publisher(Float64MultiArray, topics.PARAMETER_ESTIMATE, publisher_qos())
        self.create_subscription(JointState, topics.JOINT_STATES, self.on_state, catch_up_qos())
        self.start_diagnostics()

    def on_state(self, msg: JointState) -> None:
        t, _names, q, qd, eff = convert.joint_state_arrays(msg)
        if not self.inputs.accept("joint_states", qd, time.monotonic()) or eff is None or eff.size != 1:
            return
        prev, self.prev = self.prev, (t, float(qd[0]))
        if prev is None or not t > prev[0]:
            return
        # the torque reported with a sample is the one held over the period ending there
        self.rls.update([[(qd[0] - prev[1]) / (t - prev[0])]], [eff[0]])
        if self.rls.n % self.every == 0:
            self.pub.publish(convert.float_array_msg(self.rls.theta))

    def extend_status(self, level, msg, values):
        values["I"] = f"{self.rls.theta[0]:.6g}"
        return level, msg, values


def make_node() -> PlantNode:
    return PendulumEstimator()
