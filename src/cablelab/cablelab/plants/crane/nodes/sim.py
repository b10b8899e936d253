"""Crane simulator node: the MuJoCo boom crane of 002 (:class:`cablelab.plants.crane.sim.CraneSim`)
driven by ``/crane/effort_commands``.

Publishes (CONTRACT sec. 2) ``/crane/joint_states`` (slew, luff, hoist: position, velocity, effort
= applied command + sensor offset + noise), the motion-capture poses ``/crane/boom_tip_pose`` and
``/crane/payload_pose`` (noise, NaN dropouts), ``/crane/ground_truth/swing`` (theta1, theta2,
rope_length), ``/clock`` and ``/plant_description`` (transient-local).

``lockstep`` (default true, :class:`cablelab.ros.lockstep.LockStep`): once commands flow, a state
is answered before the simulation advances, so a slow controller slows it down instead of
destabilising it (``lockstep_timeout`` s unanswered: real time until commands flow). Without a
fresh command the drives hold the crane like a brake (:meth:`..sim.CraneSim.drive`), reported on
/diagnostics. Parameters: :data:`.parameters.SIM`.
"""
from __future__ import annotations

from geometry_msgs.msg import PoseStamped
from sensor_msgs.msg import JointState
from std_msgs.msg import Float64MultiArray

from .. import topics
from ..markers import state_markers
from ..model import JOINTS
from ..sim import live_sim
from ....ros import convert
from ....ros.inputs import ERROR
from ....ros.lockstep import LockStep
from ....ros.simulator import ADVANCE, SimulatorNode
from ....ros.status import add_problem
from .parameters import SIM as PARAMETERS


class CraneSimNode(SimulatorNode):
    def __init__(self):
        super().__init__()
        v = self.declare_params(PARAMETERS)
        desc, self.sim = live_sim(self.get_name(), v)
        self.rate, self.u = v.rate, None
        self.lock = LockStep(v.lockstep, wait_first=False, timeout=v.lockstep_timeout)
        self.start_gate()
        self.pub_js, self.pub_tip, self.pub_pay, self.pub_truth = self.state_publishers(
            (JointState, topics.JOINT_STATES), (PoseStamped, topics.TIP_POSE),
            (PoseStamped, topics.PAYLOAD_POSE), (JointState, topics.SWING_TRUTH))
        self.command_input(topics.EFFORT_COMMANDS, 3, v.command_timeout)
        self.start_simulation(desc, 1.0 / self.rate, topics.MARKERS,
                              lambda: state_markers(desc, self.sim.state()[1]), v.markers_rate)

    def extend_status(self, level, msg, values):
        s = self.sim
        values.update({"fallback (hold) steps": str(s.held), "simulation resets": str(s.resets)})
        if s.resets:
            level, msg = add_problem(level, msg, ERROR, f"simulation diverged {s.resets} times "
                                     "(restored at rest): commands too large?")
        return super().extend_status(level, msg, values)

    def on_command(self, msg: Float64MultiArray) -> None:
        values = self.take_command("effort_commands", msg, self.lock)
        if values is not None:
            self.u = values.copy()       # (never applied late; lock-step starts with the next)

    def step(self, kind: str, fresh: bool) -> None:
        self.sim.drive(self.u, 1.0 / self.rate, answered=kind == ADVANCE, fresh=fresh,
                       lockstep=self.lock.enabled)

    def publish_state(self) -> None:
        t, q, qd = self.sim.state()
        self.lock.published(t)
        m = self.sim.measurement()
        self.clock.publish(t)
        self.pub_js.publish(convert.joint_state_msg(t, JOINTS, m["joints"], m["joint_rates"], m["effort"]))
        self.pub_tip.publish(convert.pose_msg(t, m["tip"], m["tip_quat"]))
        self.pub_pay.publish(convert.pose_msg(t, m["payload"], m["payload_quat"]))
        self.pub_truth.publish(convert.joint_state_msg(t, ("theta1", "theta2", "rope_length"),
                                                       [q[3], q[4], q[2]], [qd[3], qd[4], qd[2]]))


def make_node() -> SimulatorNode:
    return CraneSimNode()
