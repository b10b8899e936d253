"""Suspended simulator node: the virtual-joint model (``model:=virtual``) or the truth plant
(``model:=truth``) of ``variant`` (:class:`~..sim.LiveSim`) in real time.

Arm position servos follow ``/suspended/reference`` (unknown joint names / wrong lengths are
rejected and counted); ``arm_input:=effort``: torque motors driven by
``/suspended/effort_commands`` (a command older than ``command_timeout`` s wall means zero torque
and WARN). Publishes ``/suspended/imu``, ``/suspended/platform_pose``, ``/suspended/joint_states``
(effort = actuator torque), ``/suspended/ground_truth/swing``,
``/suspended/ground_truth/virtual_joints`` (virtual model), ``/clock``, ``/plant_description``.

``lockstep`` (needs ``arm_input:=effort``, :class:`cablelab.ros.lockstep.LockStep`): a state is
answered before the simulation advances one period, so DDS latency and CPU load slow the run
instead of delaying the stiff arm loop (the state resent every ``lockstep_resend`` s while
waiting; ``lockstep_timeout`` s unanswered: real time with zero torque until commands flow). Use
``rate:=1000``: the LiCAS joint-3 loop (k_d / I ~ 1000 1/s) is unstable with a 10 ms hold.
Parameters: ``cable_sim_node --plant suspended --help``.
"""
from __future__ import annotations

import time

from geometry_msgs.msg import PoseStamped
from rclpy.duration import Duration
from sensor_msgs.msg import Imu, JointState
from std_msgs.msg import Float64MultiArray
from trajectory_msgs.msg import JointTrajectory

from . import arm_reference
from .. import topics
from ..bag import description_yaml
from ..markers import state_markers
from ..mjcf import VJ
from ..params import parameter_set
from ..sim import LiveSim
from ..swing import CHANNELS
from ....description import load_description
from ....errors import CablelabError
from ....ros import convert
from ....ros.clock import ClockPublisher
from ....ros.lockstep import FREE, LockStep
from ....ros.markers import start_markers
from ....ros.plant_node import PlantNode
from ....ros.qos import publisher_qos, stream_qos
from ....rotations import wxyz_to_xyzw
from .parameters import SIM as PARAMETERS


class SuspendedSimNode(PlantNode):
    def __init__(self):
        super().__init__("cable_sim_node")
        v = self.declare_params(PARAMETERS)
        self.motors = v.arm_input == "effort"
        if v.lockstep and not self.motors:
            raise CablelabError("cable_sim_node suspended: parameter lockstep=true needs "
                                "arm_input=effort (lock-step waits for effort commands)")
        self.description = load_description(description_yaml(v.variant, name=f"simulated {v.variant}"))
        self.sim = LiveSim(parameter_set(v.variant), v.model, arm_motors=self.motors, rate=v.rate,
                           start=(v.start_swing_x, v.start_swing_y, v.start_yaw), pose_noise=v.pose_noise)
        self.names = self.sim.names
        self.duration = v.duration
        self.done = False
        self.lock = LockStep(v.lockstep, wait_first=True, timeout=v.lockstep_timeout, resend=v.lockstep_resend)
        self.start_gate()
        self.use_fast_executor()
        self.inputs.add("reference", timeout=1e9, length=len(self.names))
        self.inputs.add("effort_commands", timeout=v.command_timeout, length=len(self.names))
        pub = lambda kind, topic: self.create_publisher(kind, topic, publisher_qos())  # noqa: E731
        self.pub_js = pub(JointState, topics.JOINT_STATES)
        self.pub_pose = pub(PoseStamped, topics.PLATFORM_POSE)
        self.pub_sw = pub(JointState, topics.GROUND_TRUTH_SWING)
        self.pub_vj = pub(JointState, topics.GROUND_TRUTH_VIRTUAL)
        self.pub_imu = pub(Imu, topics.IMU) if v.imu else None
        self.clock = ClockPublisher(self)
        self.publish_description(self.description)
        if self.motors:
            self.create_subscription(Float64MultiArray, topics.EFFORT_COMMANDS, self.on_effort, stream_qos())
        else:
            self.create_subscription(JointTrajectory, topics.REFERENCE, self.on_reference, stream_qos())
        self.start_diagnostics()
        self.timer = self.create_timer(1.0 / v.rate, self.tick)
        sim = self.sim
        start_markers(self, topics.MARKERS, lambda: state_markers(sim.p, sim.model, sim.data),
                      lambda: float(sim.data.time), v.markers_rate)
        self.publish_state()

    def extend_status(self, level, msg, values):
        values["sim time s"] = f"{self.sim.t:.3f}"
        values["stale answers ignored (lock-step)"] = str(self.lock.stale_answers)
        return level, msg, values

    def on_reference(self, msg: JointTrajectory) -> None:
        ref = arm_reference(self, msg, self.names)
        if ref is not None:
            self.sim.hold(ref[0])

    def on_effort(self, msg: Float64MultiArray) -> None:
        u = self.take_command("effort_commands", msg, self.lock)
        if u is not None:
            self.sim.hold(u)
            if self.lock.enabled:
                self.advance()        # lock-step: the answer is here, step at once

    def tick(self) -> None:
        step = self.may_step(self.lock, self.pub_js, self.publish_state, max(self.lock.resend, 0.5))
        if step is None:
            return
        if self.motors and step == FREE and not self.inputs.fresh("effort_commands", time.monotonic()):
            self.sim.hold(0.0)        # stale command: no torque (reported)
        self.advance()

    def advance(self) -> None:
        """One publishing period of physics, then the new state out."""
        if self.done:
            return
        self.sim.advance()
        self.publish_state()
        if self.duration and self.sim.t >= self.duration - 1e-9:
            self.done = True          # the runner stops the node (exit 0)

    def shutdown(self) -> None:
        """Before the node goes (e.g. ``duration`` reached): wait (at most 5 s per topic) until
        the subscribers acknowledged what was published, so a recorder that lags behind the
        lock-step loop still gets the end of the run."""
        for pub in (self.pub_pose, self.pub_imu, self.pub_js, self.pub_sw, self.pub_vj):
            if pub is not None:
                pub.wait_for_all_acked(Duration(seconds=5.0))

    def publish_state(self) -> None:
        """Publish the current state: IMU, pose, then joint states (the estimator then has the
        IMU sample of a pose's stamp, and a controller the attitude of the state it answers)."""
        r = self.sim.read(imu=self.pub_imu is not None)
        quat = wxyz_to_xyzw(r.quat[None])[0]
        if self.pub_imu is not None:
            self.pub_imu.publish(convert.imu_msg(r.t, quat, r.gyro, r.acc, frame_id="platform"))
        self.pub_pose.publish(convert.pose_msg(r.t, r.pos_measured, quat))
        self.pub_js.publish(convert.joint_state_msg(r.t, self.names, r.q, r.qd, r.effort))
        self.pub_sw.publish(convert.joint_state_msg(r.t, list(CHANNELS), r.swing))
        if r.virtual is not None:
            self.pub_vj.publish(convert.joint_state_msg(r.t, list(VJ), r.virtual))
        self.clock.publish(r.t)
        self.lock.published(r.t)


def make_node() -> PlantNode:
    return SuspendedSimNode()
