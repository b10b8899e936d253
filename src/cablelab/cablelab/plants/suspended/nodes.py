"""ROS 2 node adapters of the suspended plant (thin shells over the library).

* ``estimator`` (``payload_estimator --plant suspended``): ``/suspended/platform_pose`` ->
  :class:`~.swing.SwingEstimator` -> ``/suspended/swing_estimate`` (names swing_x, swing_y, yaw,
  r_x, r_y; position and velocity), stamped like the pose. ``/suspended/imu`` when present
  (spec 5.2): yaw from its orientation and yaw rate from its gyro for poses within
  ``imu_max_lag`` s (stamps) of an IMU sample, else from the pose; a stale (``imu_timeout`` s
  wall) or NaN IMU is reported on /diagnostics once the IMU has been seen. NaN, wrong-length and frozen-stamp
  poses are held and counted on /diagnostics.
* ``sim`` (``cable_sim_node --plant suspended``): the virtual-joint model (``model:=virtual``)
  or the truth plant (``model:=truth``) of ``variant`` in real time; arm position servos follow
  ``/suspended/reference`` (JointTrajectory, arm joint names; unknown names / wrong lengths are
  rejected and counted). Publishes ``/suspended/joint_states`` (effort = servo torque),
  ``/suspended/platform_pose`` (``pose_noise`` m), ``/suspended/ground_truth/swing``,
  ``/suspended/ground_truth/virtual_joints`` (virtual model), ``/clock``,
  ``/plant_description``. ``arm_input:=effort``: torque motors driven by ``/suspended/effort_commands`` instead (a
  stale command, older than ``command_timeout`` s wall, means zero torque and WARN).
  ``lockstep`` (default false; needs ``arm_input:=effort``): after publishing a state the
  simulation waits for the command answering it and advances one period (``rate``) as soon as
  it arrives, so DDS latency and CPU load slow the run down instead of delaying the stiff arm
  loop (:class:`cablelab.ros.lockstep.LockStep`, time starts with the first answer; the state is
  resent every ``lockstep_resend`` s while waiting; ``lockstep_timeout`` s without an answer:
  real time with zero torque until commands flow again). Use ``rate:=1000`` (one physics step
  per command): the LiCAS joint-3 loop (k_d / I ~ 1000 1/s) is unstable with a 10 ms hold.
* ``controller`` (``pd_feedforward --plant suspended``): on each ``/suspended/joint_states``
  publishes ``/suspended/effort_commands`` = :func:`~.controller.pd_gravity` with the gravity
  under the attitude of ``/suspended/platform_pose``; reference from ``/suspended/reference``
  plus the built-in ``excitation`` (000 Fig. 7) and ``sway_damping`` k_s (r_y rate of
  ``/suspended/swing_estimate``). ``pose_sync``: a joint state is answered only once the pose of
  the same stamp arrived, so the gravity term uses the attitude of that instant however DDS
  orders the two topics.

ROS parameters of each role: :data:`PARAMETERS` (``cable_sim_node --plant suspended --help``, ...).
"""
from __future__ import annotations

import math
import time

from ...errors import CablelabError
from ...ros.params import START_GATE, Param, executor_params, merge
from .params import VARIANTS, parameter_set
from .swing import CHANNELS, SwingEstimator

__all__ = ["make_node", "add_arguments", "ROLES", "PARAMETERS"]

ROLES = ("estimator", "sim", "controller")

_VARIANT = Param("variant", "licas", "which platform: LiCAS or CRANEbot", choices=VARIANTS)
PARAMETERS = {
    "estimator": merge((
        Param("suspension_point", [float(x) for x in parameter_set("licas").S], "suspension point "
              "S [x, y, z] (default: the LiCAS repo set)", "m", length=(3,), ge=-1e3, le=1e3),
        Param("rest_position", [float("nan")] * 3, "rest position [x, y, z] (NaN: the mean over the "
              "first rest_window s)", "m", length=(3,), ge=-1e3, le=1e3, nan=True),
        Param("rest_yaw", float("nan"), "rest yaw (NaN: the mean over the first rest_window s)", "rad",
              ge=-10.0, le=10.0, nan=True),
        Param("rest_window", 2.0, "time the rest pose is averaged over", "s", gt=0.0, le=3600.0),
        Param("imu_max_lag", 0.05, "yaw and yaw rate come from the IMU for poses within this of an "
              "IMU sample (stamps)", "s", ge=0.0, le=10.0),
        Param("velocity_tau", 0.05, "time constant smoothing the swing rates", "s", gt=0.0, le=10.0),
        Param("pose_timeout", 0.5, "a pose older than this is stale", "s wall", gt=0.0),
        Param("imu_timeout", 0.5, "an IMU sample older than this is stale (once the IMU was seen)",
              "s wall", gt=0.0),
    ), executor_params(True)),
    "sim": merge((
        _VARIANT,
        Param("model", "virtual", "the virtual-joint model or the four-tendon truth plant",
              choices=("virtual", "truth")),
        Param("start_swing_x", 0.0, "initial swing about x", "rad", ge=-1.5, le=1.5),
        Param("start_swing_y", 0.0, "initial swing about y", "rad", ge=-1.5, le=1.5),
        Param("start_yaw", 0.0, "initial yaw", "rad", ge=-3.2, le=3.2),
        Param("arm_input", "reference", "arm drives: position servos following /suspended/reference "
              "or torque motors driven by /suspended/effort_commands", choices=("reference", "effort")),
        Param("pose_noise", 0.0, "standard deviation of the measured platform position", "m",
              ge=0.0, le=10.0),
        Param("rate", 100.0, "publishing rate = command sampling (use 1000 with arm_input effort)",
              "Hz", ge=1.0, le=10000.0),
        Param("duration", 0.0, "simulated time after which the node exits (0 = run for ever)", "s",
              ge=0.0),
        Param("lockstep", False, "after a state, wait for the command answering it (needs "
              "arm_input effort)"),
        Param("lockstep_timeout", 10.0, "lock-step: without an answer for this long, real time with "
              "zero torque until commands flow again", "s wall", gt=0.0),
        Param("lockstep_resend", 0.25, "lock-step: the state is resent this often while waiting",
              "s wall", gt=0.0, le=60.0),
        Param("command_timeout", 0.5, "an effort command older than this means zero torque (WARN)",
              "s wall", gt=0.0),
        Param("imu", True, "publish /suspended/imu (orientation, gyro, accelerometer in the "
              "platform frame)"),
    ), START_GATE, executor_params(True)),
    "controller": merge((
        _VARIANT,
        Param("excitation", "none", "built-in excitation of 000 Fig. 7 added to the reference",
              choices=("none", "x", "y", "z"),
              convert=lambda v: "y" if v is True else v),     # (YAML reads a bare y as true)
        Param("excitation_level", 1, "level of the built-in excitation", ge=0, le=2),
        Param("sway_damping", 0.0, "sway damping gain k_s on the r_y rate of /suspended/swing_estimate",
              ge=0.0, le=1e3),
        Param("estimate_stale", 0.2, "a swing estimate older than this (stamps) turns sway damping "
              "off", "s", gt=0.0),
        Param("pose_sync", False, "answer a joint state only once the pose of the same stamp "
              "arrived (while poses flow)"),
    ), executor_params(True)),
}


def _estimator_class():
    import numpy as np
    from geometry_msgs.msg import PoseStamped
    from ...ros.plant_node import PlantNode
    from sensor_msgs.msg import Imu, JointState

    from ...ros import convert
    from ...ros.inputs import WARN
    from ...ros.qos import catch_up_qos, publisher_qos

    class SuspendedSwingEstimator(PlantNode):
        def __init__(self):
            super().__init__("payload_estimator")
            v = self.declare_params(PARAMETERS["estimator"])
            rest, rest_yaw = v.rest_position, v.rest_yaw
            self.est = SwingEstimator(v.suspension_point, rest_window=v.rest_window,
                                      imu_max_lag=v.imu_max_lag,
                                      rest_pos=rest if all(map(math.isfinite, rest)) else None,
                                      rest_yaw=rest_yaw if math.isfinite(rest_yaw) else None,
                                      velocity_tau=v.velocity_tau)
            self.use_fast_executor()
            self.inputs.add("platform_pose", timeout=v.pose_timeout, length=3)
            self.imu_timeout = v.imu_timeout
            self.imu_used = 0            # estimates whose yaw came from the IMU
            self.rejected = 0
            self.last_problem = ""
            self.pub = self.create_publisher(JointState, "/suspended/swing_estimate", publisher_qos())
            self.create_subscription(Imu, "/suspended/imu", self.on_imu, catch_up_qos())
            self.create_subscription(PoseStamped, "/suspended/platform_pose", self.on_pose, catch_up_qos())
            self.start_diagnostics()

        def on_imu(self, msg: Imu) -> None:
            """Optional input: monitored (stale / NaN on /diagnostics) from its first message on."""
            if "imu" not in self.inputs.inputs:
                self.inputs.add("imu", timeout=self.imu_timeout, length=7, required=False)
            t, qx, gyro, _ = convert.imu_arrays(msg)
            if qx is None or gyro is None:
                self.inputs.accept("imu", None, time.monotonic())
                return
            if self.inputs.accept("imu", np.r_[qx, gyro], time.monotonic()):
                self.est.imu(t, qx[[3, 0, 1, 2]], gyro)

        def extend_status(self, level, msg, values):
            values["yaw from IMU"] = str(self.imu_used)
            values["held samples"] = str(self.rejected)
            if self.rejected:
                level = max(level, WARN)
                extra = f"{self.rejected} pose samples held ({self.last_problem})"
                msg = extra if msg == "ok" else f"{msg}; {extra}"
            return level, msg, values

        def on_pose(self, msg: PoseStamped) -> None:
            t, pos, quat_xyzw = convert.pose_arrays(msg)
            self.inputs.accept("platform_pose", pos, time.monotonic())
            q = quat_xyzw[[3, 0, 1, 2]] if quat_xyzw is not None and len(quat_xyzw) == 4 else quat_xyzw
            s = self.est.step(t, pos, q)
            self.imu_used += s.source == "imu"
            if not s.ok:
                self.rejected += 1
                self.last_problem = s.message
                return
            self.pub.publish(convert.joint_state_msg(t, list(CHANNELS), s.position, s.velocity))

    return SuspendedSwingEstimator


def _sim_class():
    import mujoco
    import numpy as np
    from geometry_msgs.msg import PoseStamped
    from ...ros.plant_node import PlantNode
    from sensor_msgs.msg import Imu, JointState
    from std_msgs.msg import Float64MultiArray
    from trajectory_msgs.msg import JointTrajectory

    from ...description import load_description
    from ...ros import convert
    from ...ros.clock import ClockPublisher
    from ...ros.lockstep import ADVANCE, FREE, RESEND, LockStep
    from ...ros.qos import publisher_qos, stream_qos
    from ...rotations import wxyz_to_xyzw
    from .bag import description_yaml
    from .mjcf import VJ, arm_joint_names, build_truth, build_virtual
    from .sim import STATE_SPEC, initial_state, platform_imu, truth_start
    from .swing import swing_from_pose

    class SuspendedSimNode(PlantNode):
        def __init__(self):
            super().__init__("cable_sim_node")
            v = self.declare_params(PARAMETERS["sim"])
            variant = v.variant
            self.kind = v.model
            self.description = load_description(description_yaml(variant, name=f"simulated {variant}"))
            self.params = parameter_set(variant)
            sx, sy, yw = v.start_swing_x, v.start_swing_y, v.start_yaw
            self.arm_input = v.arm_input
            motors = self.arm_input == "effort"
            if self.kind == "truth":
                self.model = build_truth(self.params, arm_motors=motors)
                x0 = truth_start(self.model, self.params, sx, sy, yw)
            elif self.kind == "virtual":
                self.model = build_virtual(self.params, arm_motors=motors)
                q0 = {"J8": sx, "J9": sy, "J7": yw}
                if self.params.level_to_swing:
                    q0.update({"J11": -sx, "J12": -sy})
                x0 = initial_state(self.model, q0)
            else:
                raise AssertionError(self.kind)       # (choices of the model parameter)
            self.data = mujoco.MjData(self.model)
            mujoco.mj_setState(self.model, self.data, x0, STATE_SPEC)
            mujoco.mj_forward(self.model, self.data)
            self.names = list(arm_joint_names(self.params))
            self.jq = [self.model.joint(n).qposadr[0] for n in self.names]
            self.jv = [self.model.joint(n).dofadr[0] for n in self.names]
            self.vq = ([self.model.joint(j).qposadr[0] for j in VJ] if self.kind == "virtual" else [])
            self.rest = np.array(self.params.S) - [0, 0, self.params.L]
            self.noise = v.pose_noise
            self.rng = np.random.default_rng(0)
            self.rate = v.rate
            self.steps = max(1, int(round(1.0 / (self.rate * self.model.opt.timestep))))
            self.duration = v.duration
            self.done = False
            lockstep = v.lockstep
            if lockstep and not motors:
                raise CablelabError("cable_sim_node suspended: parameter lockstep=true needs "
                                    "arm_input=effort (lock-step waits for effort commands)")
            self.lock = LockStep(lockstep, wait_first=True,
                                 timeout=v.lockstep_timeout, resend=v.lockstep_resend)
            self.start_gate()
            self.use_fast_executor()
            self.site = self.model.site("platform").id
            self.inputs.add("reference", timeout=1e9, length=len(self.names))
            self.inputs.add("effort_commands", timeout=v.command_timeout,
                            length=len(self.names))
            self.pub_js = self.create_publisher(JointState, "/suspended/joint_states", publisher_qos())
            self.pub_pose = self.create_publisher(PoseStamped, "/suspended/platform_pose", publisher_qos())
            self.pub_sw = self.create_publisher(JointState, "/suspended/ground_truth/swing", publisher_qos())
            self.pub_vj = self.create_publisher(JointState, "/suspended/ground_truth/virtual_joints", publisher_qos())
            self.pub_imu = (self.create_publisher(Imu, "/suspended/imu", publisher_qos())
                            if v.imu else None)
            self.clock = ClockPublisher(self)
            self.publish_description(self.description)
            if motors:
                self.create_subscription(Float64MultiArray, "/suspended/effort_commands", self.on_effort, stream_qos())
            else:
                self.create_subscription(JointTrajectory, "/suspended/reference", self.on_reference, stream_qos())
            self.start_diagnostics()
            self.timer = self.create_timer(1.0 / self.rate, self.tick)
            self.publish_state()

        def extend_status(self, level, msg, values):
            values["sim time s"] = f"{self.data.time:.3f}"
            values["stale answers ignored (lock-step)"] = str(self.lock.stale_answers)
            return level, msg, values

        def on_reference(self, msg: JointTrajectory) -> None:
            _, names, q, _, _ = convert.joint_trajectory_point(msg)
            if q is None or names != self.names or len(q) != len(self.names) or not np.all(np.isfinite(q)):
                self.inputs.accept("reference", None, time.monotonic())
                return
            if self.inputs.accept("reference", q, time.monotonic()):
                self.data.ctrl[:len(q)] = q

        def on_effort(self, msg: Float64MultiArray) -> None:
            u = convert.float_array(msg)
            if not self.inputs.accept("effort_commands", u, time.monotonic()):
                return
            if self.lock.offer(convert.command_stamp(msg)):     # False: answers an earlier state
                self.data.ctrl[:len(self.names)] = u
                if self.lock.enabled:
                    self.advance()        # lock-step: the answer is here, step at once

        def tick(self) -> None:
            now = time.monotonic()
            if self.waiting_for_subscribers(self.pub_js, self.lock.published_at, self.publish_state,
                                            max(self.lock.resend, 0.5)):
                return
            step = self.lock.poll(now)
            if step == RESEND:
                self.publish_state()      # the controller may have missed it (not connected yet)
            if step not in (ADVANCE, FREE):
                return
            if self.arm_input == "effort" and step == FREE and \
                    not self.inputs.fresh("effort_commands", now):
                self.data.ctrl[:len(self.names)] = 0.0      # stale command: no torque (reported)
            self.advance()

        def advance(self) -> None:
            """One publishing period of physics, then the new state out."""
            if self.done:
                return
            for _ in range(self.steps):
                mujoco.mj_step(self.model, self.data)
            self.publish_state()
            if self.duration and self.data.time >= self.duration - 1e-9:
                self.done = True          # the runner stops the node (exit 0)

        def shutdown(self) -> None:
            """Before the node goes (e.g. ``duration`` reached): wait (at most 5 s per topic) until
            the subscribers acknowledged what was published, so a recorder that lags behind the
            lock-step loop still gets the end of the run."""
            from rclpy.duration import Duration

            for pub in (self.pub_pose, self.pub_imu, self.pub_js, self.pub_sw, self.pub_vj):
                if pub is not None:
                    pub.wait_for_all_acked(Duration(seconds=5.0))

        def publish_state(self) -> None:
            """Publish the current state: IMU, pose, then joint states (the estimator then has the
            IMU sample of a pose's stamp, and a controller the attitude of the state it answers)."""
            mujoco.mj_forward(self.model, self.data)
            t = float(self.data.time)
            pos, quat = self.data.sensordata[:3].copy(), self.data.sensordata[3:7].copy()
            q, qd = self.data.qpos[self.jq], self.data.qvel[self.jv]
            eff = self.data.qfrc_actuator[self.jv]
            if self.pub_imu is not None:
                gyro, acc = platform_imu(self.model, self.data, self.site)
                self.pub_imu.publish(convert.imu_msg(t, wxyz_to_xyzw(quat[None])[0], gyro, acc,
                                                     frame_id="platform"))
            meas = pos + (self.rng.normal(0, self.noise, 3) if self.noise > 0 else 0.0)
            self.pub_pose.publish(convert.pose_msg(t, meas, wxyz_to_xyzw(quat[None])[0]))
            self.pub_js.publish(convert.joint_state_msg(t, self.names, q, qd, eff))
            sw = swing_from_pose(pos[None], quat[None], self.params.S, rest_pos=self.rest, rest_yaw=0.0)
            self.pub_sw.publish(convert.joint_state_msg(t, list(CHANNELS), [float(sw[k][0]) for k in CHANNELS]))
            if self.vq:
                self.pub_vj.publish(convert.joint_state_msg(t, list(VJ), self.data.qpos[self.vq]))
            self.clock.publish(t)
            self.lock.published(t)

    return SuspendedSimNode


def _controller_class():
    import numpy as np
    from geometry_msgs.msg import PoseStamped
    from ...ros.plant_node import PlantNode
    from sensor_msgs.msg import JointState
    from std_msgs.msg import Float64MultiArray
    from trajectory_msgs.msg import JointTrajectory

    from ...ros import convert
    from ...ros.qos import catch_up_qos, publisher_qos, stream_qos
    from .control import ArmGravity, fig7_excitation, gains, pd_gravity, sway_offset
    from .mjcf import arm_joint_names

    class SuspendedController(PlantNode):
        def __init__(self):
            super().__init__("pd_feedforward")
            v = self.declare_params(PARAMETERS["controller"])
            self.params = parameter_set(v.variant)
            self.names = list(arm_joint_names(self.params))
            n = len(self.names)
            self.kp, self.kd, self.lim = gains(self.params)
            self.use_fast_executor()
            self.gravity = ArmGravity(self.params)
            self.excitation = v.excitation
            self.level = v.excitation_level
            self.k_s = v.sway_damping
            self.stale = v.estimate_stale
            self.pose_sync = v.pose_sync
            self.pose_t = -np.inf
            self.pending = None          # pose_sync: joint state waiting for its pose
            self.q_ref, self.qd_ref = np.zeros(n), np.zeros(n)
            self.R = np.eye(3)
            self.v_swing, self.t_swing = np.nan, -np.inf
            self.inputs.add("joint_states", timeout=0.5, length=n)
            self.inputs.add("platform_pose", timeout=0.5, length=3)
            self.inputs.add("reference", timeout=1e9, length=n)
            self.pub = self.create_publisher(Float64MultiArray, "/suspended/effort_commands", publisher_qos())
            # (pose first: an executor taking one sample per topic per round in creation order then
            # has the attitude of a state before the state, as the simulator publishes them)
            self.create_subscription(PoseStamped, "/suspended/platform_pose", self.on_pose, catch_up_qos())
            self.create_subscription(JointState, "/suspended/joint_states", self.on_joints, catch_up_qos())
            self.create_subscription(JointState, "/suspended/swing_estimate", self.on_swing, catch_up_qos())
            self.create_subscription(JointTrajectory, "/suspended/reference", self.on_reference, stream_qos())
            self.start_diagnostics()

        def on_pose(self, msg: PoseStamped) -> None:
            t, pos, qx = convert.pose_arrays(msg)
            if self.inputs.accept("platform_pose", pos, time.monotonic()) and np.all(np.isfinite(qx)):
                from ...rotations import quat_to_matrix, xyzw_to_wxyz

                self.R = quat_to_matrix(xyzw_to_wxyz(qx / np.linalg.norm(qx)))
                self.pose_t = t
                if self.pending is not None and t >= self.pending[0] - 1e-9:
                    self.answer(*self.pending)       # pose_sync: the attitude of that instant is here

        def on_swing(self, msg: JointState) -> None:
            t, names, _, qd, _ = convert.joint_state_arrays(msg)
            if qd is not None and "r_y" in names and len(qd) == len(names) and np.isfinite(qd[names.index("r_y")]):
                self.v_swing, self.t_swing = float(qd[names.index("r_y")]), t

        def on_reference(self, msg: JointTrajectory) -> None:
            _, names, q, qd, _ = convert.joint_trajectory_point(msg)
            if q is None or names != self.names or len(q) != len(self.names) or not np.all(np.isfinite(q)):
                self.inputs.accept("reference", None, time.monotonic())
                return
            if self.inputs.accept("reference", q, time.monotonic()):
                self.q_ref = q
                self.qd_ref = qd if qd is not None and len(qd) == len(q) else np.zeros_like(q)

        def on_joints(self, msg: JointState) -> None:
            t, names, q, qd, _ = convert.joint_state_arrays(msg)
            ok = q is not None and qd is not None and names == self.names and len(q) == len(names)
            if not self.inputs.accept("joint_states", q if ok else None, time.monotonic()) or not ok \
                    or not np.all(np.isfinite(qd)):
                return
            self.pending = None
            if self.pose_sync and self.pose_t < t - 1e-9 and self.inputs.fresh("platform_pose", time.monotonic()):
                self.pending = (t, q, qd)            # answered when the pose of stamp t arrives
                return
            self.answer(t, q, qd)

        def answer(self, t, q, qd) -> None:
            """Publish the command answering the joint state of stamp ``t``."""
            self.pending = None
            q_ref, qd_ref = self.q_ref.copy(), self.qd_ref.copy()
            if self.excitation in ("x", "y", "z"):
                qe, qde = fig7_excitation(np.array([t]), self.params, self.excitation, self.level)
                q_ref, qd_ref = q_ref + qe[0], qd_ref + qde[0]
            off = sway_offset(self.v_swing, self.k_s, t - self.t_swing, stale=self.stale)
            n = self.params.n_arm
            q_ref[1] += off
            q_ref[n + 1] += off
            tau = pd_gravity(q, qd, q_ref, qd_ref, self.kp, self.kd, self.gravity.torque(q, self.R), self.lim)
            self.pub.publish(convert.command_msg(tau, t))

    return SuspendedController


def add_arguments(role: str, parser) -> None:
    """No command-line options beyond the ROS parameters."""


def make_node(role: str, args=None):
    """The node of ``role`` (``estimator``)."""
    if role == "estimator":
        return _estimator_class()()
    if role == "sim":
        return _sim_class()()
    if role == "controller":
        return _controller_class()()
    raise CablelabError(f"suspended: node role {role!r} is not implemented (available: {', '.join(ROLES)})")
