"""``cable_sim_node --plant pendulum``: the simulator (:class:`~..sim.PendulumSim`) at ``rate`` Hz of
simulated time, as fast as ``realtime_factor`` allows, until ``duration`` s. The torque is the
built-in chirp (:func:`~..control.chirp`, ``drive:=builtin``) or the latest
``/pendulum/effort_commands`` (``drive:=topic``; a stale command means zero torque). Publishes
``/pendulum/joint_states`` (angle, rate, applied torque plus ``torque_noise``), ``/clock`` and
``/plant_description``. ROS parameters: :data:`PARAMETERS`.
"""
from __future__ import annotations

import time
from pathlib import Path

import numpy as np
from sensor_msgs.msg import JointState
from std_msgs.msg import Float64MultiArray

from cablelab.description import load_description
from cablelab.ros import convert
from cablelab.ros.clock import ClockPublisher
from cablelab.ros.params import START_GATE, Param
from cablelab.ros.plant_node import PlantNode
from cablelab.ros.qos import publisher_qos, stream_qos

from .. import topics
from ..control import chirp
from ..mjcf import JOINT
from ..sim import PendulumSim

DEFAULT_DESCRIPTION = Path(__file__).resolve().parent.parent / "data" / "pendulum.yaml"

PARAMETERS = (
    Param("description", "", "plant description: YAML file or text (empty = the package's data/pendulum.yaml)"),
    Param("damping", 0.05, "hinge damping (the effect the nominal model lacks)", "N m s/rad", ge=0.0, le=100.0),
    Param("drive", "builtin", "the torque: the built-in chirp or /pendulum/effort_commands",
          choices=("builtin", "topic")),
    Param("rate", 200.0, "publishing rate", "Hz", ge=1.0, le=1000.0),
    Param("duration", 8.0, "simulated time after which the node exits", "s", gt=0.0, le=3600.0),
    Param("realtime_factor", 4.0, "simulated seconds per wall second", gt=0.0, le=1000.0),
    Param("torque_noise", 0.01, "standard deviation of the measured torque", "N m", ge=0.0, le=100.0),
    Param("seed", 0, "seed of the noise generator", ge=0),
    Param("command_timeout", 0.5, "a command older than this means zero torque", "s wall", gt=0.0),
) + START_GATE


class PendulumSimNode(PlantNode):
    def __init__(self):
        super().__init__("cable_sim_node")
        v = self.declare_params(PARAMETERS)
        desc = load_description(v.description or DEFAULT_DESCRIPTION)
        self.sim = PendulumSim(desc.pendulum, v.damping)
        self.rate, self.duration, self.noise = v.rate, v.duration, v.torque_noise
        self.builtin = v.drive == "builtin"
        self.rng = np.random.default_rng(v.seed)
        self.command = 0.0
        self.done = False
        self.inputs.add("effort_commands", timeout=v.command_timeout, length=1, required=not self.builtin)
        self.start_gate()
        self.publish_description(desc)
        self.pub = self.create_publisher(JointState, topics.JOINT_STATES, publisher_qos())
        self.create_subscription(Float64MultiArray, topics.EFFORT_COMMANDS, self.on_command, stream_qos())
        self.clock = ClockPublisher(self)
        self.last_publish = time.monotonic()
        self.start_diagnostics()
        self.create_timer(1.0 / (self.rate * v.realtime_factor), self.tick)

    def on_command(self, msg: Float64MultiArray) -> None:
        values = convert.float_array(msg)
        if self.inputs.accept("effort_commands", values, time.monotonic()):
            self.command = float(values[0])

    def publish(self, tau: float) -> None:
        t, q, qd = self.sim.state()
        self.clock.publish(t)
        measured = tau + self.noise * self.rng.standard_normal()
        self.pub.publish(convert.joint_state_msg(t, [JOINT], [q], [qd], [measured]))
        self.last_publish = time.monotonic()

    def tick(self) -> None:
        if self.done or self.waiting_for_subscribers(self.pub, self.last_publish, lambda: self.publish(0.0)):
            return
        if self.builtin:
            tau = float(chirp(self.sim.t, self.duration))
        else:
            tau = self.command if self.inputs.fresh("effort_commands", time.monotonic()) else 0.0
        self.sim.advance(tau, 1.0 / self.rate)
        self.publish(tau)
        self.done = self.sim.t >= self.duration

    def extend_status(self, level, msg, values):
        values["sim time s"] = f"{self.sim.t:.3f}"
        return level, msg, values


def make_node() -> PlantNode:
    return PendulumSimNode()
