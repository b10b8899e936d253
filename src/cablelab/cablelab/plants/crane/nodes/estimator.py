"""Crane swing estimator node: theta1, theta2 and rope length from motion capture, live.

Inputs: ``/crane/boom_tip_pose`` and ``/crane/payload_pose`` (PoseStamped, same stamps) and the
slew angle from ``/crane/joint_states``, paired by stamp (:class:`..posepairs.PairedSwing`). Each
pair goes through :class:`..swing.SwingTracker` (the exact inverse of CONTRACT sec. 2 in the slewing
frame, 002 sec. 6.3; velocities by smoothed differences) to ``/crane/swing_estimate`` (names
theta1, theta2, rope_length; position and velocity) stamped like the poses. Dropouts (NaN poses),
frozen stamps and gaps are counted and reported on /diagnostics. Parameters: :data:`.parameters.ESTIMATOR`.
"""
from __future__ import annotations

from geometry_msgs.msg import PoseStamped
from sensor_msgs.msg import JointState

from .. import topics
from ..posepairs import PairedSwing
from ....ros import convert
from ....ros.inputs import WARN
from ....ros.plant_node import PlantNode
from ....ros.qos import catch_up_qos, publisher_qos
from ....ros.status import add_problem
from .parameters import ESTIMATOR as PARAMETERS

NAMES = ["theta1", "theta2", "rope_length"]


class CraneSwingEstimator(PlantNode):
    def __init__(self):
        super().__init__("payload_estimator")
        v = self.declare_params(PARAMETERS)
        self.swing = PairedSwing(v.max_wait, v.velocity_tau)
        self.inputs.add("boom_tip_pose", timeout=v.pose_timeout, length=3)
        self.inputs.add("payload_pose", timeout=v.pose_timeout, length=3)
        self.inputs.add("slew", timeout=v.slew_timeout, length=1)
        self.pub = self.create_publisher(JointState, topics.SWING_ESTIMATE, publisher_qos())
        self.create_subscription(JointState, topics.JOINT_STATES, self.on_joints, catch_up_qos())
        self.create_subscription(PoseStamped, topics.TIP_POSE, self.on_tip, catch_up_qos())
        self.create_subscription(PoseStamped, topics.PAYLOAD_POSE, self.on_payload, catch_up_qos())
        self.start_diagnostics()

    def extend_status(self, level, msg, values):
        problem, own = self.swing.report()
        values.update(own)
        if problem:
            level, msg = add_problem(level, msg, WARN, problem)
        return level, msg, values

    def on_joints(self, msg: JointState) -> None:
        t, names, q, _qd, _eff = convert.joint_state_arrays(msg)
        ok = q is not None and "slew" in names and len(names) == q.size
        if self.accept("slew", [q[names.index("slew")]] if ok else None):
            self.swing.pairs.slew(t, q[names.index("slew")])
            self.process()

    def on_tip(self, msg: PoseStamped) -> None:
        t, pos, _ = convert.pose_arrays(msg)
        self.accept("boom_tip_pose", pos)   # NaN is counted as rejected
        self.swing.pairs.tip_pose(t, pos)

    def on_payload(self, msg: PoseStamped) -> None:
        t, pos, _ = convert.pose_arrays(msg)
        self.accept("payload_pose", pos)
        self.swing.pairs.payload_pose(t, pos)
        self.process()

    def process(self) -> None:
        """Publish the estimate of every pose pair whose slew angle is known
        (:meth:`PairedSwing.estimates <cablelab.plants.crane.posepairs.PairedSwing.estimates>`)."""
        for t, x, v in self.swing.estimates():
            self.pub.publish(convert.joint_state_msg(t, NAMES, x, v))


def make_node() -> PlantNode:
    return CraneSwingEstimator()
