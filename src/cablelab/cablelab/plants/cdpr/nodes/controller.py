"""CDPR controller node: PD on motor angles + mass feedforward (PDFF, 001 Fig. 6, eq. 14-15).

Each ``/cdpr/joint_states`` sample gives one ``/cdpr/effort_commands`` (motor torques, N m, order
winch_1..n; pre-serialised, naming the stamp of the state it answers for a lock-step simulator)
from :class:`cablelab.plants.cdpr.live.LiveController`: motor-angle PD with the inverse geometric
model of the reference ``/cdpr/reference`` (or a played ``reference_bag``, published there),
feedforward of 001 eq. 14 with the live ``/cdpr/payload_estimate`` (``feedforward`` true, PDFF)
or none (PD), friction compensation (eq. 15) and a minimum-tension floor. A stale or implausible
estimate falls back to the nominal mass (WARN on /diagnostics). Without a reference (or with a
bad motor state) nothing is published (the simulator's brakes hold) and /diagnostics says why.
Matching samples by stamp: :class:`cablelab.plants.cdpr.streams.CommandStream`.
Parameters: :data:`.parameters.CONTROLLER` (``pd_feedforward --plant cdpr --help``).
"""
from __future__ import annotations

import math
import time

from geometry_msgs.msg import InertiaStamped
from sensor_msgs.msg import JointState
from std_msgs.msg import Float64MultiArray
from trajectory_msgs.msg import MultiDOFJointTrajectory

from .. import topics
from ..streams import CommandStream, controller_config
from ....ros import convert
from ....ros.plant_node import PlantNode
from ....ros.qos import publisher_qos, stream_qos
from ....ros.rawmsg import CommandTemplate
from ....rotations import xyzw_to_wxyz
from .parameters import CONTROLLER as PARAMETERS


class CdprController(PlantNode):
    def __init__(self):
        super().__init__("pd_feedforward", start_parameter_services=False)  # smaller wait set
        v = self.v = self.declare_params(PARAMETERS)
        self.stream = CommandStream(v.feedforward, v.sync_wait, v.estimate_wait)
        self.sent = 0
        self._cmd = CommandTemplate("winch")     # pre-serialised commands naming their state's stamp
        self.inputs.add("joint_states", timeout=v.state_timeout)
        self.inputs.add("reference", timeout=v.reference_timeout)
        self.inputs.add("payload_estimate", timeout=v.estimate_timeout, length=1, required=False)
        self.pub_cmd = self.create_publisher(Float64MultiArray, topics.EFFORT_COMMANDS, publisher_qos())
        self.listen_for_description(v.description, keep_first=True)     # it configures the law
        # the reference and the estimate as bytes in deep queues (a busy moment delays samples,
        # drops none); they wake nobody: the reference (published before its state) and the
        # estimate wait queued until a state or the timer takes them (an awaited estimate still
        # wakes the node). The states keep-last 1: after a busy moment the newest state is
        # answered, not a backlog whose commands the simulator would only count as stale
        q = stream_qos(1000)
        self.subscribe(MultiDOFJointTrajectory, topics.REFERENCE, self.on_reference, q, raw=True, polled=True)
        self.subscribe(InertiaStamped, topics.PAYLOAD_ESTIMATE, self.on_estimate, q,
                       polled=not self.stream.awaits_estimate)
        self.create_subscription(JointState, topics.JOINT_STATES, self.on_state, stream_qos(1), raw=True)
        self.player = self.play_reference(v.reference_bag, topics.REFERENCE, ("x", "y", "z"), platform=True)
        self._state_wall = -1.0     # wall time of the last state taken
        self.timer = self.create_timer(0.002, self.on_timer)
        self.use_fast_executor()
        self.start_diagnostics()
        # /diagnostics runs after a command or from the timer, never between a state and its command
        self.defer_timers(t for t in self.timers if t is not self.timer)

    @property
    def controller(self):
        return self.stream.controller

    def set_description(self, desc) -> None:
        self.stream.describe(desc.cdpr, desc.gravity, controller_config(
            self.v, 0.0 if desc.cdpr is None else desc.cdpr.platform_mass))
        if desc.cdpr is not None:
            super().set_description(desc)
            self.inputs.set_length("joint_states", len(desc.cdpr.cables))

    def on_reference(self, msg: MultiDOFJointTrajectory) -> None:
        """A reference sample (MultiDOFJointTrajectory or its serialised bytes)."""
        r = self.decode_raw("reference", MultiDOFJointTrajectory, msg)
        if r is not None and self.accept("reference", r["position"]):     # (position None when empty)
            self.stream.reference(r["t"], r["position"], xyzw_to_wxyz(r["quaternion"]),
                                  r["linear_velocity"], r["linear_acceleration"])
            self.command(self.stream.ready())

    def on_estimate(self, msg: InertiaStamped) -> None:
        t, m, com = convert.inertia_arrays(msg)
        self.stream.estimate(t, m if self.accept("payload_estimate", [m]) else None, com)
        self.command(self.stream.ready())     # a state may have been waiting for this estimate

    def on_state(self, msg: JointState) -> None:
        """A motor state (JointState or its bytes): commanded now if the reference of its stamp is
        here, else a little later (:meth:`on_timer`: DDS does not order samples across topics).
        The queued reference and estimate are taken after the command when the reference terms
        were prepared ahead (:meth:`CommandStream.prepare_next <cablelab.plants.cdpr.streams.
        CommandStream.prepare_next>`), then a due /diagnostics: the state -> command path stays
        short."""
        state = self.decode_raw("joint_states", JointState, msg)
        if state is None:
            return
        self._state_wall = now = time.monotonic()
        if self.player is not None and math.isfinite(state[0]):
            self.player(state[0], ())        # the designed reference of this stamp, published first
        if self.stream.needs_inputs_first(state[0]):
            self.take_polled()          # the reference and estimate that came before it
        self.stream.state(state, now)
        self.command(self.stream.ready())
        self.take_polled()              # then prepare the next stamp's terms, off this path
        self.stream.prepare_next(state[0])
        self.run_deferred()

    def on_timer(self) -> None:
        """A state still waiting for the reference (or the awaited estimate) of its stamp is
        commanded once they came or it waited long enough; while states flow, their own callback
        takes the queued inputs and the timer only runs a due /diagnostics."""
        now = time.monotonic()
        if self.stream.pending is not None or now - self._state_wall > 0.01:
            self.take_polled()
            self.command(self.stream.ready(now))
        self.run_deferred()

    def command(self, state) -> None:
        """One command for ``state`` = (t, names, position, velocity, effort), if any."""
        if state is None:
            return
        t0 = time.perf_counter()
        if (tau := self.stream.command(state, self.inputs, time.monotonic())) is not None:
            self.pub_cmd.publish(self._cmd.data(tau, state[0]))   # naming the state it answers (lock-step)
            self.sent += 1
            self.latency.since(t0)

    def extend_status(self, level, msg, values):
        return self.stream.report(level, msg, values, "PDFF" if self.v.feedforward else "PD", self.sent)


def make_node() -> PlantNode:
    return CdprController()
