"""Suspended arm controller node: on each ``/suspended/joint_states`` publishes
``/suspended/effort_commands`` = :class:`~..control.ArmLaw` (PD + the arms' gravity under the
attitude of ``/suspended/platform_pose``); reference from ``/suspended/reference`` plus the
built-in ``excitation`` (000 Fig. 7) and ``sway_damping`` k_s (r_y rate of
``/suspended/swing_estimate``). ``pose_sync``: a joint state is answered only once the pose of the
same stamp arrived (:class:`~..posesync.PoseSync`), so the gravity term uses the attitude of that
instant however DDS orders the two topics. Parameters: :data:`.parameters.CONTROLLER`.
"""
from __future__ import annotations

import time

import numpy as np
from geometry_msgs.msg import PoseStamped
from sensor_msgs.msg import JointState
from std_msgs.msg import Float64MultiArray

from .. import topics
from ..control import ArmLaw
from ..mjcf import arm_joint_names
from ..params import parameter_set
from ..posesync import PoseSync
from ....ros import convert
from ....ros.plant_node import PlantNode
from ....ros.qos import catch_up_qos, publisher_qos
from ....ros.reference import FollowedReference
from .parameters import CONTROLLER as PARAMETERS


class SuspendedController(PlantNode):
    def __init__(self):
        super().__init__("pd_feedforward")
        v = self.declare_params(PARAMETERS)
        params = parameter_set(v.variant)
        self.names = list(arm_joint_names(params))
        n = len(self.names)
        self.law = ArmLaw(params, v.excitation, v.excitation_level, v.sway_damping, v.estimate_stale)
        self.use_fast_executor()
        self.sync = PoseSync(v.pose_sync)
        self.at_rest = (np.zeros(n), np.zeros(n))      # the reference until one arrives
        self.v_swing, self.t_swing = np.nan, -np.inf
        self.inputs.add("joint_states", timeout=0.5, length=n)
        self.inputs.add("platform_pose", timeout=0.5, length=3)
        self.pub = self.create_publisher(Float64MultiArray, topics.EFFORT_COMMANDS, publisher_qos())
        # (pose first: an executor taking one sample per topic per round in creation order then
        # has the attitude of a state before the state, as the simulator publishes them)
        self.create_subscription(PoseStamped, topics.PLATFORM_POSE, self.on_pose, catch_up_qos())
        self.create_subscription(JointState, topics.JOINT_STATES, self.on_joints, catch_up_qos())
        self.create_subscription(JointState, topics.SWING_ESTIMATE, self.on_swing, catch_up_qos())
        self.reference = FollowedReference(self, topics.REFERENCE, self.names, timeout=1e9)
        self.start_diagnostics()

    def on_pose(self, msg: PoseStamped) -> None:
        t, pos, qx = convert.pose_arrays(msg)
        if self.accept("platform_pose", pos) and np.all(np.isfinite(qx)):
            self.answer(self.sync.pose(t, qx))      # a held state: the attitude of its instant is here

    def on_swing(self, msg: JointState) -> None:
        t, names, _, qd, _ = convert.joint_state_arrays(msg)
        if qd is not None and "r_y" in names and len(qd) == len(names) and np.isfinite(qd[names.index("r_y")]):
            self.v_swing, self.t_swing = float(qd[names.index("r_y")]), t

    def on_joints(self, msg: JointState) -> None:
        t, names, q, qd, _ = convert.joint_state_arrays(msg)
        ok = q is not None and qd is not None and names == self.names and len(q) == len(names)
        if self.accept("joint_states", q if ok else None) and ok and np.all(np.isfinite(qd)):
            self.answer(self.sync.state(t, q, qd, self.inputs.fresh("platform_pose", time.monotonic())))

    def answer(self, state) -> None:
        """Publish the command answering the joint state ``(t, q, qd)`` (nothing for None)."""
        if state is not None:
            t, q, qd = state
            q_ref, qd_ref = (self.reference(t, q) or self.at_rest)[:2]
            tau = self.law.torque(t, q, qd, q_ref, qd_ref, self.sync.R, self.v_swing, t - self.t_swing)
            self.pub.publish(convert.command_msg(tau, t))


def make_node() -> PlantNode:
    return SuspendedController()
