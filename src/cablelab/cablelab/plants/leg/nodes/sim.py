"""Leg simulator node: steps the hybrid plant (:class:`~..live.LiveLeg`) at ``rate`` with the latest
``/leg/effort_commands`` torque (stale -> 0) and publishes ``/leg/joint_states`` (``body``: encoder
height, backward-difference velocity, F_in; ``motor``: theta, 0, torque), ``/leg/contact``,
``/leg/ground_truth/state``, ``/clock`` and ``/plant_description``. ``lockstep``: the start state
is published (and resent every ``lockstep_resend`` s) until the torque answering it arrives, and
from then on a state is followed by the torque answering it (estimator and controller in between)
before the simulation advances (:class:`cablelab.ros.lockstep.LockStep`), so a loaded machine
slows the run down instead of delaying the stance torque by a whole flight, and no stance passes
without the controller while the nodes are still discovering each other (in real time the leg
fell from its start height and bounced with zero torque for the 0.4 s the controller's commands
took to arrive on an idle machine, a recording unlike any the controller makes).
Parameters: :data:`.parameters.SIM`.
"""
from __future__ import annotations

import math

from sensor_msgs.msg import JointState
from std_msgs.msg import Float64MultiArray

from . import hop_msg
from .. import topics
from ..description import load_leg_description
from ..live import LiveLeg
from ..markers import sim_markers
from ....ros import convert
from ....ros.lockstep import LockStep
from ....ros.simulator import SimulatorNode
from .parameters import SIM as PARAMETERS


class LegSimNode(SimulatorNode):
    def __init__(self):
        super().__init__()
        v = self.declare_params(PARAMETERS)
        desc = load_leg_description(v.description)
        self.leg = LiveLeg(desc, v.mass_scale, v.preload, v.z0_offset, v.rate)
        self.sim, self.tau, self.reading = self.leg.sim, 0.0, self.leg.reading()
        self.lock = LockStep(v.lockstep, wait_first=True, timeout=v.lockstep_timeout, resend=v.lockstep_resend)
        self.pub_js, self.pub_contact, self.pub_truth = self.state_publishers(
            (JointState, topics.JOINT_STATES), (JointState, topics.CONTACT), (JointState, topics.GROUND_TRUTH))
        self.command_input(topics.EFFORT_COMMANDS, 1, v.command_timeout, required=False)
        self.start_gate()
        self.start_simulation(desc, 1.0 / v.rate, topics.MARKERS, lambda: sim_markers(self.sim),
                              v.markers_rate, publish_first=v.lockstep)

    def extend_status(self, level, msg, values):
        values["events"] = str(len(self.sim.events))
        return super().extend_status(level, msg or "ok", values)

    def on_command(self, msg: Float64MultiArray) -> None:
        values = self.take_command("effort_commands", msg, self.lock)
        if values is not None:
            self.tau = float(values[0])

    def step(self, kind: str, fresh: bool) -> None:
        if not fresh:
            self.tau = 0.0
        self.reading = self.leg.step(self.tau)      # (z, zd, theta) of the encoder

    def publish_state(self) -> None:
        s, (z, zd, theta) = self.sim, self.reading
        self.clock.publish(s.t)
        self.lock.published(s.t)
        # the switch before the height: the estimator reads the phase of this sample with it
        self.pub_contact.publish(convert.joint_state_msg(s.t, ["contact"], [float(s.phase)]))
        self.pub_js.publish(convert.joint_state_msg(s.t, ["body", "motor"], [z, theta], [zd, 0.0],
                                                    [s.f_in, self.tau]))
        apex_time = s.events[-1].t if s.events else math.nan
        self.pub_truth.publish(hop_msg(s.t, s.z, s.zd, s.phase, math.nan, apex_time, s.grf()))


def make_node() -> SimulatorNode:
    return LegSimNode()
