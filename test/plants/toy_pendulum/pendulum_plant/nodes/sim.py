"""``cable_sim_node --plant pendulum``: a MuJoCo damped pendulum driven by a chirp torque.

Publishes ``/pendulum/joint_states`` (hinge angle, rate, applied torque), ``/clock`` and
``/plant_description`` at ``rate`` Hz of simulated time, as fast as ``realtime_factor`` allows, and
exits after ``duration`` s of simulated time. The measured torque carries white noise
(``torque_noise``, N m), like a current-based torque estimate. ROS parameters: :data:`PARAMETERS`.
"""
from __future__ import annotations

import time

import mujoco
import numpy as np
from sensor_msgs.msg import JointState

from cablelab.description import load_description
from cablelab.ros import convert
from cablelab.ros.clock import ClockPublisher
from cablelab.ros.params import START_GATE, Param
from cablelab.ros.plant_node import PlantNode
from cablelab.ros.qos import publisher_qos

DESCRIPTION = "plant: pendulum\nname: toy damped pendulum\npendulum: {mass: 0.5, length: 0.4}\n"


def mjcf(mass: float, length: float, damping: float) -> str:
    """A hinge about world y with a point-like bob ``length`` below it (q = 0 hanging down)."""
    return f"""<mujoco><option timestep="0.001" integrator="implicitfast"/>
  <worldbody><body><joint name="hinge" type="hinge" axis="0 -1 0" damping="{damping}"/>
    <geom type="sphere" size="0.01" pos="0 0 -{length}" mass="{mass}"/></body></worldbody>
  <actuator><motor joint="hinge" name="tau"/></actuator></mujoco>"""


PARAMETERS = (
    Param("description", "", "plant description: YAML file or text (empty = a 0.5 kg, 0.4 m pendulum)"),
    Param("damping", 0.05, "hinge damping (the hidden effect)", "N m s/rad", ge=0.0, le=100.0),
    Param("rate", 200.0, "publishing rate", "Hz", ge=1.0, le=1000.0),
    Param("duration", 8.0, "simulated time after which the node exits", "s", gt=0.0, le=3600.0),
    Param("realtime_factor", 4.0, "simulated seconds per wall second", gt=0.0, le=1000.0),
    Param("torque_noise", 0.01, "standard deviation of the measured torque", "N m", ge=0.0, le=100.0),
    Param("seed", 0, "seed of the noise generator", ge=0),
) + START_GATE


class PendulumSim(PlantNode):
    def __init__(self):
        super().__init__("cable_sim_node")
        v = self.declare_params(PARAMETERS)
        desc = load_description(v.description or DESCRIPTION)
        sec = desc.pendulum
        self.model = mujoco.MjModel.from_xml_string(mjcf(sec.mass, sec.length, v.damping))
        self.data = mujoco.MjData(self.model)
        self.rate = v.rate
        self.duration = v.duration
        self.speed = v.realtime_factor
        self.noise = v.torque_noise
        self.rng = np.random.default_rng(v.seed)
        self.steps = max(1, int(round(1.0 / (self.rate * self.model.opt.timestep))))
        self.done = False
        self.start_gate()
        self.publish_description(desc)
        self.pub = self.create_publisher(JointState, "/pendulum/joint_states", publisher_qos())
        self.clock = ClockPublisher(self)
        self.last_publish = time.monotonic()
        self.start_diagnostics()
        self.create_timer(1.0 / (self.rate * self.speed), self.tick)

    def torque(self, t: float) -> float:
        """Chirp 0.2 -> 2 Hz, 0.3 N m."""
        return 0.3 * np.sin(2 * np.pi * (0.2 * t + 0.9 * t * t / max(self.duration, 1e-9)))

    def publish(self, tau: float) -> None:
        t = float(self.data.time)
        self.clock.publish(t)
        measured = tau + self.noise * self.rng.standard_normal()
        self.pub.publish(convert.joint_state_msg(t, ["hinge"], [self.data.qpos[0]],
                                                 [self.data.qvel[0]], [measured]))
        self.last_publish = time.monotonic()

    def tick(self) -> None:
        if self.done or self.waiting_for_subscribers(self.pub, self.last_publish,
                                                     lambda: self.publish(0.0)):
            return
        tau = self.torque(self.data.time)
        self.data.ctrl[0] = tau
        for _ in range(self.steps):
            mujoco.mj_step(self.model, self.data)
        self.publish(tau)
        self.done = self.data.time >= self.duration

    def extend_status(self, level, msg, values):
        values["sim time s"] = f"{self.data.time:.3f}"
        return level, msg, values


def make_node() -> PlantNode:
    return PendulumSim()
