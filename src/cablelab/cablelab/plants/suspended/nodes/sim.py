"""Suspended simulator node: the virtual-joint model (``model:=virtual``) or the truth plant
(``model:=truth``) of ``variant`` (:class:`~..sim.LiveSim`) in real time.

Arm position servos follow ``/suspended/reference`` (wrong names or lengths rejected and counted),
or (``arm_input:=effort``) torque motors ``/suspended/effort_commands`` (older than
``command_timeout`` s wall: zero torque, WARN). Publishes ``/suspended/{imu, platform_pose,
joint_states, ground_truth/swing, ground_truth/virtual_joints}``, ``/clock``, ``/plant_description``.
``lockstep`` (needs ``arm_input:=effort``, :class:`cablelab.ros.lockstep.LockStep`): a state is
answered before the simulation advances, so DDS latency and CPU load slow the run instead of
delaying the stiff arm loop. Use ``rate:=1000``: the LiCAS joint-3 loop (k_d / I ~ 1000 1/s) is
unstable with a 10 ms hold. Parameters: :data:`.parameters.SIM`.
"""
from __future__ import annotations

from geometry_msgs.msg import PoseStamped
from sensor_msgs.msg import Imu, JointState
from std_msgs.msg import Float64MultiArray
from trajectory_msgs.msg import JointTrajectory

from . import arm_reference
from .. import topics
from ..bag import description_yaml
from ..markers import state_markers
from ..mjcf import VJ
from ..sim import LiveSim
from ..swing import CHANNELS
from ....description import load_description
from ....ros import convert
from ....ros.lockstep import LockStep
from ....ros.qos import stream_qos
from ....ros.simulator import FREE, SimulatorNode
from ....rotations import wxyz_to_xyzw
from .parameters import SIM as PARAMETERS, check_sim


class SuspendedSimNode(SimulatorNode):
    def __init__(self):
        super().__init__()
        v = self.declare_params(PARAMETERS)
        check_sim(v)
        desc = load_description(description_yaml(v.variant, name=f"simulated {v.variant}"))
        self.motors, self.duration = v.arm_input == "effort", v.duration
        self.sim = sim = LiveSim.of_parameters(v)
        self.names = sim.names
        self.lock = LockStep(v.lockstep, wait_first=True, timeout=v.lockstep_timeout, resend=v.lockstep_resend)
        self.republish_every = max(v.lockstep_resend, 0.5)
        self.start_gate()
        self.use_fast_executor()
        self.inputs.add("reference", timeout=1e9, length=len(self.names))
        self.inputs.add("effort_commands", timeout=v.command_timeout, length=len(self.names))
        self.pub_js, self.pub_pose, self.pub_sw, self.pub_vj, self.pub_imu = self.state_publishers(
            (JointState, topics.JOINT_STATES), (PoseStamped, topics.PLATFORM_POSE),
            (JointState, topics.GROUND_TRUTH_SWING), (JointState, topics.GROUND_TRUTH_VIRTUAL),
            (Imu, topics.IMU if v.imu else None))
        if self.motors:
            self.create_subscription(Float64MultiArray, topics.EFFORT_COMMANDS, self.on_effort, stream_qos())
        else:
            self.create_subscription(JointTrajectory, topics.REFERENCE, self.on_reference, stream_qos())
        self.start_simulation(desc, 1.0 / v.rate, topics.MARKERS,
                              lambda: state_markers(sim.p, sim.model, sim.data), v.markers_rate)

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

    def step(self, kind: str, fresh: bool) -> None:
        if self.motors and kind == FREE and not fresh:
            self.sim.hold(0.0)        # stale command: no torque (reported)
        self.sim.advance()

    def publish_state(self) -> None:
        """IMU, pose, then joint states: the estimator then has the IMU sample of a pose's
        stamp, and a controller the attitude of the state it answers."""
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


def make_node() -> SimulatorNode:
    return SuspendedSimNode()
