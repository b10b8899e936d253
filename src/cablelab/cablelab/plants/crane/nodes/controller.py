"""Crane controller node: joint PD + gravity compensation + reference-acceleration feedforward
(002 sec. 5.3.1, :func:`..control.joint_command`) answering every ``/crane/joint_states`` on
``/crane/effort_commands`` [slew N m, luff N m, hoist N], stamped like the state it answers.

Gravity and inertia come from ``/plant_description`` and the latest ``/crane/swing_estimate``
(optional; a hanging payload without it). The reference is ``/crane/reference``, the built-in
multi-sine excitation or a ``reference_bag`` (both published on ``/crane/reference``;
:class:`cablelab.ros.reference.FollowedReference`); with a stale one the node holds the crane where
it is (gravity compensation + damping) and reports WARN. Parameters: :data:`.parameters.CONTROLLER`.
"""
from __future__ import annotations

import time

from sensor_msgs.msg import JointState
from std_msgs.msg import Float64MultiArray

from .. import topics
from ..control import Gains, joint_command
from ..model import JOINTS, CraneParams
from ..reference import reference_trajectory
from ....ros import convert
from ....ros.inputs import WARN
from ....ros.plant_node import PlantNode
from ....ros.qos import publisher_qos, stream_qos
from ....ros.reference import FollowedReference
from ....ros.status import add_problem
from .parameters import CONTROLLER as PARAMETERS


class CraneController(PlantNode):
    def __init__(self):
        super().__init__("pd_feedforward")
        v = self.declare_params(PARAMETERS)
        self.gains, self.feedforward = Gains(tuple(v.kp), tuple(v.kd)), v.feedforward
        self.inertias = {"slew_inertia": v.slew_inertia, "luff_inertia": v.luff_inertia}
        self.params, self.swing, self.fallbacks = None, None, 0
        seed = v.excitation_seed
        excitation = (lambda t, q0: reference_trajectory(t, q0=tuple(q0), seed=seed)) \
            if v.reference_source == "excitation" else None
        self.reference = FollowedReference(self, topics.REFERENCE, JOINTS, v.reference_bag, excitation,
                                           v.reference_timeout)
        self.inputs.add("joint_states", timeout=0.5, length=3)
        self.inputs.add("swing_estimate", timeout=0.5, length=2, required=False)
        self.pub_cmd = self.create_publisher(Float64MultiArray, topics.EFFORT_COMMANDS, publisher_qos())
        self.create_subscription(JointState, topics.JOINT_STATES, self.on_state, stream_qos())
        self.create_subscription(JointState, topics.SWING_ESTIMATE, self.on_swing, stream_qos())
        self.listen_for_description()
        self.start_diagnostics()

    def extend_status(self, level, msg, values):
        values["fallback (hold) commands"] = str(self.fallbacks)
        if self.params is None:
            level, msg = add_problem(level, msg, WARN, "waiting for /plant_description")
        return level, msg, values

    def set_description(self, desc) -> None:
        super().set_description(desc)
        if desc.crane is None:
            self.get_logger().error("/plant_description has no crane section")
            return
        self.params = CraneParams.from_description(desc, **self.inertias)

    def on_swing(self, msg: JointState) -> None:
        swing = convert.named_positions(msg, ("theta1", "theta2"))
        if self.accept("swing_estimate", swing):
            self.swing = swing

    def on_state(self, msg: JointState) -> None:
        t, names, q, qd, _ = convert.joint_state_arrays(msg)
        if not self.accept("joint_states", q if list(names) == list(JOINTS) else None) or self.params is None:
            return
        fresh_swing = self.swing is not None and self.inputs.fresh("swing_estimate", time.monotonic())
        ref = self.reference(t, q)
        self.fallbacks += ref is None          # no fresh reference: hold where it is
        u = joint_command(q, qd, ref, self.params, self.gains, self.swing[None] if fresh_swing else None,
                          self.feedforward)
        self.pub_cmd.publish(convert.command_msg(u, stamp=t, label="joints"))


def make_node() -> PlantNode:
    return CraneController()
