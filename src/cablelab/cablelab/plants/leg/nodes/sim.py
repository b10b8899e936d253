"""Leg simulator node: steps the hybrid plant (:class:`~..sim.LegSim`) at ``rate`` with the latest
``/leg/effort_commands`` torque (stale -> 0) and publishes ``/leg/joint_states`` (``body``: encoder
height, backward-difference velocity, F_in; ``motor``: theta, 0, torque), ``/leg/contact``,
``/leg/ground_truth/state``, ``/clock`` and ``/plant_description``.

ROS parameters: :data:`PARAMETERS` (``cable_sim_node --plant leg --help``).
"""
from __future__ import annotations

import math
import time

from std_msgs.msg import Float64MultiArray
from sensor_msgs.msg import JointState

from . import hop_msg
from .. import topics
from ..description import leg_of, load_leg_description
from ..hybrid import STANCE
from ..markers import sim_markers
from ..sim import LegSim, motor_angle, quantise
from ....ros import convert
from ....ros.clock import ClockPublisher
from ....ros.markers import start_markers
from ....ros.plant_node import PlantNode
from ....ros.qos import publisher_qos, stream_qos
from .parameters import SIM as PARAMETERS


class LegSimNode(PlantNode):
    def __init__(self):
        super().__init__("cable_sim_node")
        v = self.declare_params(PARAMETERS)
        self.description = load_leg_description(v.description)
        leg = leg_of(self.description)
        nominal = leg.params(self.description.gravity)
        truth = nominal.replace(m=nominal.m * v.mass_scale,
                                F0=nominal.F0 if math.isnan(v.preload) else v.preload)
        self.res = leg.encoder_resolution
        self.rate = v.rate
        self.sim = LegSim(truth, nominal.z_td + v.z0_offset, 0.0, dt=1.0 / self.rate)
        self.tau = 0.0
        self._z_prev = None
        self.inputs.add("effort_commands", timeout=v.command_timeout, length=1, required=False)
        self.pub_js = self.create_publisher(JointState, topics.JOINT_STATES, publisher_qos())
        self.pub_contact = self.create_publisher(JointState, topics.CONTACT, publisher_qos())
        self.pub_truth = self.create_publisher(JointState, topics.GROUND_TRUTH, publisher_qos())
        self.clock = ClockPublisher(self)
        self.publish_description(self.description)
        self.create_subscription(Float64MultiArray, topics.EFFORT_COMMANDS, self.on_command, stream_qos())
        self.start_diagnostics()
        self.timer = self.create_timer(1.0 / self.rate, self.tick)
        start_markers(self, topics.MARKERS, lambda: sim_markers(self.sim), lambda: self.sim.t, v.markers_rate)

    def extend_status(self, level, msg, values):
        values["sim time s"] = f"{self.sim.t:.3f}"
        values["events"] = str(len(self.sim.events))
        return level, msg or "ok", values

    def on_command(self, msg: Float64MultiArray) -> None:
        values = self.take_command("effort_commands", msg)
        if values is not None:
            self.tau = float(values[0])

    def tick(self) -> None:
        if not self.inputs.fresh("effort_commands", time.monotonic()):
            self.tau = 0.0
        s = self.sim
        s.step(self.tau if s.phase == STANCE else 0.0)
        zq = float(quantise(s.z, self.res))
        zd_m = 0.0 if self._z_prev is None else (zq - self._z_prev) * self.rate   # backward difference
        self._z_prev = zq
        self.clock.publish(s.t)
        self.pub_js.publish(convert.joint_state_msg(s.t, ["body", "motor"], [zq, float(motor_angle(zq, s.p.L))],
                                                    [zd_m, 0.0], [s.f_in, self.tau]))
        self.pub_contact.publish(convert.joint_state_msg(s.t, ["contact"], [float(s.phase)]))
        apex_time = s.events[-1].t if s.events else math.nan
        self.pub_truth.publish(hop_msg(s.t, s.z, s.zd, s.phase, math.nan, apex_time, s.grf()))


def make_node() -> PlantNode:
    return LegSimNode()
