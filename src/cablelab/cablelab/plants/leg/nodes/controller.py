"""Leg controller node: ``/leg/hop_estimate`` (+ ``/leg/reference`` apex height, or a schedule
written by ``cablelab excite``: ``reference_bag``, played from the first estimate on and published
on ``/leg/reference``) -> :class:`~..control.ApexController` -> ``/leg/effort_commands``.

Parameters: :data:`.parameters.CONTROLLER`.
"""
from __future__ import annotations

import math
import time

import numpy as np
from sensor_msgs.msg import JointState
from std_msgs.msg import Float64MultiArray
from trajectory_msgs.msg import JointTrajectory

from .. import topics
from ..control import ApexController
from ..description import leg_of, load_leg_description
from ....ros import convert
from ....ros.plant_node import PlantNode
from ....ros.qos import publisher_qos, stream_qos
from ....ros.reference import ReferencePlayer
from .parameters import CONTROLLER as PARAMETERS


class LegControllerNode(PlantNode):
    def __init__(self):
        super().__init__("pd_feedforward")
        v = self.declare_params(PARAMETERS)
        self.description = load_leg_description(v.description)
        params = leg_of(self.description).params(self.description.gravity)
        self.ctl = ApexController(params, params.z_td + v.h_des, T=v.T, P=v.P, k_i=v.k_i, k_ff=v.k_ff,
                                  T_max=v.T_max, mode=v.mode)
        self.player = ReferencePlayer.from_bag(self, v.reference_bag, topics.REFERENCE, ["apex_height"]) \
            if v.reference_bag else None
        self.inputs.add("hop_estimate", timeout=0.5)
        self.inputs.add("reference", timeout=math.inf, length=1, required=False)
        self.pub = self.create_publisher(Float64MultiArray, topics.EFFORT_COMMANDS, publisher_qos())
        self.create_subscription(JointState, topics.HOP_ESTIMATE, self.on_estimate, stream_qos())
        if self.player is None:
            self.create_subscription(JointTrajectory, topics.REFERENCE, self.on_reference, stream_qos())
        self.start_diagnostics()

    def extend_status(self, level, msg, values):
        values.update({"T N m": f"{self.ctl.T:.4f}", "h_des m": f"{self.ctl.h_des:.4f}", "mode": self.ctl.mode})
        return level, msg or "ok", values

    def on_reference(self, msg: JointTrajectory) -> None:
        _, _, pos, _, _ = convert.joint_trajectory_point(msg)
        if pos is not None and self.accept("reference", pos):
            self.ctl.h_des = float(np.asarray(pos).ravel()[0])

    def on_estimate(self, msg: JointState) -> None:
        t, names, pos, vel, _ = convert.joint_state_arrays(msg)
        if pos is None or vel is None or "phase" not in names or not self.inputs.accept(
                "hop_estimate", pos[[names.index("phase")]], time.monotonic()):
            return  # hold T (stale or NaN estimate)
        if self.player is not None:
            self.ctl.h_des = float(self.player(t, pos)[0][0])
        ia = names.index("apex_height")
        tau = self.ctl.step(t, int(round(pos[names.index("phase")])), float(pos[ia]), float(vel[ia]))
        self.pub.publish(convert.command_msg([tau], stamp=t))


def make_node() -> PlantNode:
    return LegControllerNode()
