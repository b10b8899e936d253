"""Crane swing estimator node: theta1, theta2 and rope length from motion capture, live.

Inputs: ``/crane/boom_tip_pose`` and ``/crane/payload_pose`` (PoseStamped, same stamps) and the
slew angle from ``/crane/joint_states``. For each pose pair it runs
:class:`cablelab.plants.crane.swing.SwingTracker` (the exact inverse of CONTRACT sec. 2 in the
slewing frame, 002 sec. 6.3; velocities by smoothed differences) and publishes
``/crane/swing_estimate`` (names theta1, theta2, rope_length; position and velocity) stamped like
the poses. Dropouts (NaN poses), frozen stamps and gaps are counted and reported on /diagnostics.

ROS parameters: :data:`PARAMETERS` (``payload_estimator --plant crane --help``).
"""
from __future__ import annotations

import time
from collections import deque

import numpy as np
from geometry_msgs.msg import PoseStamped
from sensor_msgs.msg import JointState

from .. import topics
from ..swing import SwingTracker
from ....ros import convert
from ....ros.inputs import WARN
from ....ros.params import Param
from ....ros.plant_node import PlantNode
from ....ros.qos import catch_up_qos, publisher_qos

NAMES = ["theta1", "theta2", "rope_length"]


PARAMETERS = (
    Param("velocity_tau", 0.02, "time constant smoothing the swing rates", "s", gt=0.0, le=10.0),
    Param("max_wait", 0.2, "a pose pair waits this long (in stamps) for the slew angle of its "
          "stamp before the latest one is used", "s", ge=0.0, le=10.0),
    Param("pose_timeout", 0.5, "a pose older than this is stale", "s wall", gt=0.0),
    Param("slew_timeout", 0.5, "a slew angle older than this is stale", "s wall", gt=0.0),
)


class CraneSwingEstimator(PlantNode):
    def __init__(self):
        super().__init__("payload_estimator")
        v = self.declare_params(PARAMETERS)
        self.tracker = SwingTracker(tau=v.velocity_tau)
        self.slews = deque(maxlen=400)      # (stamp, slew angle) of /crane/joint_states
        self.pending = deque(maxlen=100)    # pose pairs waiting for the slew angle of their stamp
        self.tip = None  # (t, position)
        self.unpaired = 0
        self.unsynced = 0
        self.max_wait = v.max_wait
        pose_timeout = v.pose_timeout
        self.inputs.add("boom_tip_pose", timeout=pose_timeout, length=3)
        self.inputs.add("payload_pose", timeout=pose_timeout, length=3)
        self.inputs.add("slew", timeout=v.slew_timeout, length=1)
        self.pub = self.create_publisher(JointState, topics.SWING_ESTIMATE, publisher_qos())
        self.create_subscription(JointState, topics.JOINT_STATES, self.on_joints, catch_up_qos())
        self.create_subscription(PoseStamped, topics.TIP_POSE, self.on_tip, catch_up_qos())
        self.create_subscription(PoseStamped, topics.PAYLOAD_POSE, self.on_payload, catch_up_qos())
        self.start_diagnostics()

    def extend_status(self, level, msg, values):
        c = self.tracker.counts
        for k, v in c.items():
            values[f"samples {k}"] = str(v)
        values["unpaired poses"] = str(self.unpaired)
        values["poses without a synchronous slew angle"] = str(self.unsynced)
        if c["dropout"] or c["frozen"] or c["irregular"]:
            level = max(level, WARN)
            extra = (f"{c['dropout']} motion-capture dropouts, {c['frozen']} frozen stamps, "
                     f"{c['irregular']} irregular periods")
            msg = extra if msg == "ok" else f"{msg}; {extra}"
        return level, msg, values

    def on_joints(self, msg: JointState) -> None:
        t, names, q, _qd, _eff = convert.joint_state_arrays(msg)
        if q is None or "slew" not in names or len(names) != q.size:
            self.inputs.accept("slew", None, time.monotonic())
            return
        val = q[names.index("slew")]
        if self.inputs.accept("slew", [val], time.monotonic()) and np.isfinite(t):
            if not self.slews or t > self.slews[-1][0]:
                self.slews.append((t, float(val)))
            self.process()

    def on_tip(self, msg: PoseStamped) -> None:
        t, pos, _ = convert.pose_arrays(msg)
        self.inputs.accept("boom_tip_pose", pos, time.monotonic())   # NaN is counted as rejected
        self.tip = (t, pos)

    def on_payload(self, msg: PoseStamped) -> None:
        t, pos, _ = convert.pose_arrays(msg)
        self.inputs.accept("payload_pose", pos, time.monotonic())
        if self.tip is None or abs(self.tip[0] - t) > 1e-6:
            self.unpaired += 1
            return
        self.pending.append((t, self.tip[1], pos))
        self.process()

    def slew_at(self, t: float) -> float | None:
        """Slew angle at stamp t (interpolated in the buffer; None if not yet received)."""
        if not self.slews or self.slews[-1][0] < t - 1e-9:
            return None
        ts = np.array([s[0] for s in self.slews])
        vs = np.unwrap(np.array([s[1] for s in self.slews]))
        return float(np.interp(t, ts, vs))

    def process(self) -> None:
        """Estimate every pending pose pair whose slew angle is known (in stamp order); a pair
        waiting longer than ``max_wait`` (s of stamps) uses the latest slew angle (counted)."""
        while self.pending:
            t, tip, pay = self.pending[0]
            slew = self.slew_at(t)
            if slew is None:
                newest = self.pending[-1][0]
                if newest - t < self.max_wait or not self.slews:
                    return
                slew = self.slews[-1][1]
                self.unsynced += 1
            self.pending.popleft()
            status, x, v = self.tracker.update(t, tip, pay, slew)
            if x is not None:
                self.pub.publish(convert.joint_state_msg(t, NAMES, x, v))


def make_node() -> PlantNode:
    return CraneSwingEstimator()
