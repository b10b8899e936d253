"""``pd_feedforward --plant pendulum``: on every ``/pendulum/joint_states`` publishes the chirp torque
(:func:`~..control.chirp`) at the state's stamp on ``/pendulum/effort_commands`` (run the simulator
with ``drive:=topic``). ROS parameters: :data:`PARAMETERS`.
"""
from __future__ import annotations

import time

from sensor_msgs.msg import JointState
from std_msgs.msg import Float64MultiArray

from cablelab.ros import convert
from cablelab.ros.params import Param
from cablelab.ros.plant_node import PlantNode
from cablelab.ros.qos import publisher_qos, stream_qos

from .. import topics
from ..control import chirp

PARAMETERS = (
    Param("duration", 8.0, "length of the chirp", "s", gt=0.0, le=3600.0),
    Param("amplitude", 0.3, "amplitude of the chirp", "N m", ge=0.0, le=1e3),
)


class PendulumController(PlantNode):
    def __init__(self):
        super().__init__("pd_feedforward")
        v = self.declare_params(PARAMETERS)
        self.duration, self.amplitude = v.duration, v.amplitude
        self.inputs.add("joint_states", timeout=0.5, length=1)
        self.pub = self.create_publisher(Float64MultiArray, topics.EFFORT_COMMANDS, publisher_qos())
        self.create_subscription(JointState, topics.JOINT_STATES, self.on_state, stream_qos())
        self.start_diagnostics()

    def on_state(self, msg: JointState) -> None:
        t, _names, q, _qd, _eff = convert.joint_state_arrays(msg)
        if self.inputs.accept("joint_states", q, time.monotonic()):
            tau = float(chirp(t, self.duration, self.amplitude))
            self.pub.publish(convert.command_msg([tau], stamp=t))


def make_node() -> PlantNode:
    return PendulumController()
