"""ROS 2 node adapters of the suspended plant (thin shells over the library).

Only the ``estimator`` role exists so far (``payload_estimator --plant suspended``):
``/suspended/platform_pose`` -> :class:`~.swing.SwingEstimator` -> ``/suspended/swing_estimate``
(names swing_x, swing_y, yaw, r_x, r_y; position and velocity), stamped like the pose. NaN,
wrong-length and frozen-stamp poses are held and counted on /diagnostics. The ``sim`` and
``controller`` roles are not written yet (their laws: :mod:`.sim`, :mod:`.controller`).

ROS parameters: ``suspension_point`` [x, y, z] m (default: the LiCAS repo set),
``rest_window`` s, ``velocity_tau`` s, ``pose_timeout`` s wall.
"""
from __future__ import annotations

import time

from ...errors import CablelabError
from .params import parameter_set
from .swing import CHANNELS, SwingEstimator

__all__ = ["make_node", "add_arguments", "ROLES"]

ROLES = ("estimator",)


def _estimator_class():
    from geometry_msgs.msg import PoseStamped
    from rclpy.node import Node
    from sensor_msgs.msg import JointState

    from ...ros import convert
    from ...ros.diagnostics import Diagnostics
    from ...ros.inputs import WARN, InputMonitor
    from ...ros.qos import catch_up_qos, publisher_qos

    class SuspendedSwingEstimator(Node):
        def __init__(self):
            super().__init__("payload_estimator")
            p = self.declare_parameter
            S = [float(v) for v in p("suspension_point", list(parameter_set("licas").S)).value]
            self.est = SwingEstimator(S, rest_window=float(p("rest_window", 2.0).value),
                                      velocity_tau=float(p("velocity_tau", 0.05).value))
            self.inputs = InputMonitor()
            self.inputs.add("platform_pose", timeout=float(p("pose_timeout", 0.5).value), length=3)
            self.rejected = 0
            self.last_problem = ""
            self.pub = self.create_publisher(JointState, "/suspended/swing_estimate", publisher_qos())
            self.create_subscription(PoseStamped, "/suspended/platform_pose", self.on_pose, catch_up_qos())
            self.diag = Diagnostics(self, update=self.status)

        def status(self):
            level, msg, values = self.inputs.status(time.monotonic())
            values["held samples"] = str(self.rejected)
            if self.rejected:
                level = max(level, WARN)
                extra = f"{self.rejected} pose samples held ({self.last_problem})"
                msg = extra if msg == "ok" else f"{msg}; {extra}"
            return level, msg, values

        def on_pose(self, msg) -> None:
            t, pos, quat_xyzw = convert.pose_arrays(msg)
            self.inputs.accept("platform_pose", pos, time.monotonic())
            q = quat_xyzw[[3, 0, 1, 2]] if quat_xyzw is not None and len(quat_xyzw) == 4 else quat_xyzw
            s = self.est.step(t, pos, q)
            if not s.ok:
                self.rejected += 1
                self.last_problem = s.message
                return
            self.pub.publish(convert.joint_state_msg(t, list(CHANNELS), s.position, s.velocity))

    return SuspendedSwingEstimator


def add_arguments(role: str, parser) -> None:
    """No command-line options beyond the ROS parameters."""


def make_node(role: str, args=None):
    """The node of ``role`` (``estimator``)."""
    if role == "estimator":
        return _estimator_class()()
    raise CablelabError(f"suspended: node role {role!r} is not implemented (available: {', '.join(ROLES)})")
