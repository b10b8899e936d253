"""Crane controller node: joint PD + gravity compensation + reference-acceleration feedforward
(002 sec. 5.3.1, :func:`cablelab.plants.crane.control.joint_command`).

On every ``/crane/joint_states`` message it publishes ``/crane/effort_commands`` [slew N m, luff
N m, hoist N] naming the stamp of the state it answers (:func:`cablelab.ros.convert.command_msg`:
a lock-step simulator applies only the answer to its latest state). Gravity and inertia come from
``/plant_description`` and the latest ``/crane/swing_estimate`` (optional; a hanging payload
without it). The reference is ``/crane/reference``, the built-in multi-sine excitation or a
``reference_bag`` (both published on ``/crane/reference``). With a stale reference the node holds
the crane where it is (gravity compensation + damping) and reports WARN.
Parameters: ``pd_feedforward --plant crane --help``.
"""
from __future__ import annotations

import time

from sensor_msgs.msg import JointState
from std_msgs.msg import Float64MultiArray
from trajectory_msgs.msg import JointTrajectory

from .. import topics
from ..control import Gains, joint_command
from ..model import JOINTS, CraneParams
from ..reference import reference_trajectory
from ....ros import convert
from ....ros.inputs import WARN
from ....ros.plant_node import PlantNode
from ....ros.qos import publisher_qos, stream_qos
from ....ros.status import add_problem
from ....ros.reference import ReferencePlayer
from .parameters import CONTROLLER as PARAMETERS


class CraneController(PlantNode):
    def __init__(self):
        super().__init__("pd_feedforward")
        v = self.declare_params(PARAMETERS)
        self.gains = Gains(tuple(v.kp), tuple(v.kd))
        self.feedforward = v.feedforward
        self.inertias = {"slew_inertia": v.slew_inertia, "luff_inertia": v.luff_inertia}
        self.params = None
        self.source = "bag" if v.reference_bag else v.reference_source
        if v.reference_bag:
            self.player = ReferencePlayer.from_bag(self, v.reference_bag, topics.REFERENCE, JOINTS)
        elif self.source == "excitation":
            seed = v.excitation_seed
            self.player = ReferencePlayer(self, topics.REFERENCE, JOINTS,
                                          lambda t, q0: reference_trajectory(t, q0=tuple(q0), seed=seed))
        self.ref = None
        self.swing = None
        self.fallbacks = 0
        self.inputs.add("joint_states", timeout=0.5, length=3)
        self.inputs.add("reference", timeout=v.reference_timeout, length=3,
                        required=self.source == "topic")
        self.inputs.add("swing_estimate", timeout=0.5, length=2, required=False)
        self.pub_cmd = self.create_publisher(Float64MultiArray, topics.EFFORT_COMMANDS, publisher_qos())
        self.create_subscription(JointState, topics.JOINT_STATES, self.on_state, stream_qos())
        self.create_subscription(JointState, topics.SWING_ESTIMATE, self.on_swing, stream_qos())
        if self.source == "topic":
            self.create_subscription(JointTrajectory, topics.REFERENCE, self.on_reference, stream_qos())
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

    def on_reference(self, msg: JointTrajectory) -> None:
        ref = convert.reference_point(msg, JOINTS)
        if self.accept("reference", None if ref is None else ref[0]):
            self.ref = ref

    def on_state(self, msg: JointState) -> None:
        t, names, q, qd, _ = convert.joint_state_arrays(msg)
        now = time.monotonic()
        if q is None or list(names) != list(JOINTS):
            self.inputs.accept("joint_states", None, now)
            return
        if not self.inputs.accept("joint_states", q, now) or self.params is None:
            return
        swing = self.swing[None] if self.swing is not None and self.inputs.fresh("swing_estimate", now) else None
        if self.source in ("excitation", "bag"):
            ref = self.player(t, q)
        else:
            ref = self.ref if self.ref is not None and self.inputs.fresh("reference", now) else None
            self.fallbacks += ref is None
        u = joint_command(q, qd, ref, self.params, self.gains, swing, self.feedforward)
        self.pub_cmd.publish(convert.command_msg(u, stamp=t, label="joints"))

def make_node() -> PlantNode:
    return CraneController()
