"""Suspended swing estimator node: ``/suspended/platform_pose`` -> :class:`~..swing.SwingEstimator`
-> ``/suspended/swing_estimate`` (names swing_x, swing_y, yaw, r_x, r_y; position and velocity),
stamped like the pose. ``/suspended/imu`` when present (spec 5.2): yaw from its orientation and
yaw rate from its gyro for poses within ``imu_max_lag`` s (stamps) of an IMU sample, else from
the pose; a stale (``imu_timeout`` s wall) or NaN IMU is reported on /diagnostics once the IMU has
been seen. NaN, wrong-length and frozen-stamp poses are held and counted on /diagnostics.
Parameters: :data:`.parameters.ESTIMATOR`.
"""
from __future__ import annotations

import numpy as np
from geometry_msgs.msg import PoseStamped
from sensor_msgs.msg import Imu, JointState

from .. import topics
from ..swing import CHANNELS, SwingEstimator
from ....ros import convert
from ....ros.inputs import WARN
from ....ros.plant_node import PlantNode
from ....ros.qos import catch_up_qos, publisher_qos
from ....ros.status import add_problem
from .parameters import ESTIMATOR as PARAMETERS


class SuspendedSwingEstimator(PlantNode):
    def __init__(self):
        super().__init__("payload_estimator")
        v = self.declare_params(PARAMETERS)
        self.est = SwingEstimator.of_parameters(v)
        self.use_fast_executor()
        self.inputs.add("platform_pose", timeout=v.pose_timeout, length=3)
        self.imu_timeout = v.imu_timeout
        self.pub = self.create_publisher(JointState, topics.SWING_ESTIMATE, publisher_qos())
        self.create_subscription(Imu, topics.IMU, self.on_imu, catch_up_qos())
        self.create_subscription(PoseStamped, topics.PLATFORM_POSE, self.on_pose, catch_up_qos())
        self.start_diagnostics()

    def on_imu(self, msg: Imu) -> None:
        """Optional input: monitored (stale / NaN on /diagnostics) from its first message on."""
        if "imu" not in self.inputs.inputs:
            self.inputs.add("imu", timeout=self.imu_timeout, length=7, required=False)
        t, qx, gyro, _ = convert.imu_arrays(msg)
        ok = qx is not None and gyro is not None
        if self.accept("imu", np.r_[qx, gyro] if ok else None) and ok:
            self.est.imu(t, qx[[3, 0, 1, 2]], gyro)

    def extend_status(self, level, msg, values):
        e = self.est
        values.update({"yaw from IMU": str(e.from_imu), "held samples": str(e.held)})
        if e.held:
            level, msg = add_problem(level, msg, WARN, f"{e.held} pose samples held ({e.last_problem})")
        return level, msg, values

    def on_pose(self, msg: PoseStamped) -> None:
        t, pos, quat_xyzw = convert.pose_arrays(msg)
        self.accept("platform_pose", pos)
        q = quat_xyzw[[3, 0, 1, 2]] if quat_xyzw is not None and len(quat_xyzw) == 4 else quat_xyzw
        s = self.est.step(t, pos, q)
        if s.ok:
            self.pub.publish(convert.joint_state_msg(t, list(CHANNELS), s.position, s.velocity))


def make_node() -> PlantNode:
    return SuspendedSwingEstimator()
