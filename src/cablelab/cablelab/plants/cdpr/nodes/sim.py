"""CDPR simulator node: the MuJoCo CAROCA of 001 (real pulleys, friction winches) driven by
``/cdpr/effort_commands``.

Publishes (CONTRACT sec. 2) ``/cdpr/joint_states`` (winch_1..n: motor angle, rate, torque from
current), ``/cdpr/cable_tensions`` (cable_1..n: paid-out length, dynamometer tension),
``/cdpr/platform_pose`` (optional), ``/cdpr/reference`` (the pick-and-place s-curve of 001 sec.
II-C, unless ``publish_reference`` is false and another node publishes it), the ground truth
``/cdpr/ground_truth/{pose,payload}``, ``/clock`` and ``/plant_description``. Physics:
:class:`cablelab.plants.cdpr.sim.CdprSim`.

Modes: ``real_time`` true steps at ``rate`` Hz of wall time; false runs as fast as possible in
lock-step with the controller (a step as soon as the command answering the last published state
arrived, or after ``lockstep_timeout`` s without one). Without a fresh command the winch brakes
lock the motor angles (the last torque + a stiff PD about the locked angles), reported as WARN on
/diagnostics; slack cables are reported too.

ROS parameters: :data:`PARAMETERS` (``cable_sim_node --plant cdpr --help``). Outgoing messages are pre-serialised templates
(:class:`cablelab.ros.rawmsg.RawTemplate`): each step only patches stamps and numbers.
"""
from __future__ import annotations

import time

import numpy as np
from geometry_msgs.msg import InertiaStamped, PoseStamped
from rosgraph_msgs.msg import Clock
from sensor_msgs.msg import JointState
from std_msgs.msg import Float64MultiArray
from trajectory_msgs.msg import MultiDOFJointTrajectory

from ....description import load_description
from ....errors import CablelabError
from ..trajectory import ReferenceTable, pick_and_place
from ....ros import convert
from ....rotations import wxyz_to_xyzw
from ....ros.inputs import WARN
from ....ros.fastspin import poll, take_newest
from ....ros.markers import start_markers
from ....ros.params import DESCRIPTION, START_GATE, Param, executor_params, merge
from ....ros.plant_node import PlantNode
from ....ros.qos import publisher_qos, stream_qos
from ....ros import rawmsg
from ....ros.rawmsg import RawTemplate
from ..geometry import check_pulley_radius
from ..hardware import WinchBrakes
from ..sim import CdprSim, CdprTruth, default_description_path


PARAMETERS = merge((
    DESCRIPTION,
    Param("payload_mass", 0.0, "payload carried by the platform (truth)", "kg", ge=0.0, le=1e5),
    Param("payload_com", [0.15, 0.0, -0.6], "payload centre of mass [x, y, z] in the platform frame "
          "(truth)", "m", length=(3,), ge=-100.0, le=100.0),
    Param("pulleys", True, "simulate the real pulleys (false: cables leave from fixed exit points)"),
    Param("winch_coulomb", 0.3, "Coulomb friction of each winch (truth)", "N m", ge=0.0, le=1e3),
    Param("winch_viscous", 0.002, "viscous friction of each winch (truth)", "N m s/rad", ge=0.0, le=1e3),
    Param("motor_inertia", 2e-4, "rotor inertia of each winch motor (truth)", "kg m^2", gt=0.0, le=10.0),
    Param("tension_noise", 5.0, "standard deviation of the dynamometer noise", "N", ge=0.0, le=1e5),
    Param("tension_bias", [0.0], "dynamometer bias: one value for all cables or one per cable", "N",
          ge=-1e5, le=1e5),
    Param("torque_noise", 0.02, "standard deviation of the motor-torque (current) noise", "N m",
          ge=0.0, le=1e4),
    Param("pose_noise", 0.0, "standard deviation of the measured platform position", "m", ge=0.0, le=10.0),
    Param("timestep", 0.0, "physics step (0 = min(2 ms, 1/rate); else at least 10 us)", "s",
          ge=0.0, le=0.01),
    Param("rate", 100.0, "publishing rate of the state = command sampling", "Hz", ge=1.0, le=10000.0),
    Param("real_time", True, "step at rate Hz of wall time (false: as fast as possible in lock-step "
          "with the controller)"),
    Param("publish_reference", True, "publish /cdpr/reference, the pick-and-place s-curve of 001 "
          "sec. II-C (false: another node publishes it)"),
    Param("reference_lead", -1.0, "time the published reference runs ahead of the state (negative "
          "= two periods in real time, 0 in lock-step)", "s", ge=-1.0, le=1.0),
    Param("publish_pose", True, "publish the measured pose /cdpr/platform_pose"),
    Param("trajectory_speed", 1.0, "time scale of the s-curve (2 = twice as fast)", gt=0.0, le=100.0),
    Param("settle", 1.0, "time held at A before the trajectory starts", "s", ge=0.0, le=3600.0),
    Param("duration", 0.0, "simulated time after which the node exits (0 = run until stopped)", "s",
          ge=0.0),
    Param("command_timeout", 0.5, "a command older than this is stale and the winch brakes hold "
          "(real time)", "s wall", gt=0.0),
    Param("lockstep_timeout", 10.0, "lock-step: the step goes ahead (brakes holding) after this long "
          "without the answering command", "s wall", gt=0.0),
    Param("extras_every", 1, "publish /clock, the measured pose and the ground truth every k-th step "
          "(lighter at 1 kHz)", ge=1, le=1000000),
    Param("mass_change", 0.0, "mass put on the platform at its centre of mass at sim time "
          "mass_change_time (a payload change while running, e.g. to test a model monitor; the "
          "ground truth follows)", "kg", ge=-1e5, le=1e5),
    Param("mass_change_time", -1.0, "sim time of the mass change (negative = never)", "s", le=1e9),
    Param("markers_rate", 30.0, "rate of the 3D view /cdpr/markers (visualization_msgs/MarkerArray "
          "in world: cables coloured by tension, platform, exit points; 0 = off)", "Hz wall",
          ge=0.0, le=1000.0),
    Param("seed", 0, "seed of the noise generator", ge=0),
), START_GATE, executor_params(True))


def truth_from_parameters(node: str, v, n: int, rate: float) -> CdprTruth:
    """The simulated CDPR's truth from the validated simulator parameters ``v`` (the specs of
    :data:`PARAMETERS`) for ``n`` cables at ``rate`` Hz; one-line errors naming ``node`` for what
    the specs alone cannot check (the bias length against the cable count, the smallest step)."""
    bias = v.tension_bias
    if len(bias) not in (1, n):
        raise CablelabError(f"{node}: parameter tension_bias:={bias}: expected 1 or {n} numbers "
                            "(one per cable) [N]")
    if 0 < v.timestep < 1e-5:
        raise CablelabError(f"{node}: parameter timestep:={v.timestep!r}: expected 0 (auto) or a step "
                            "of at least 1e-05 [s]")
    return CdprTruth(
        pulleys=v.pulleys, payload_mass=v.payload_mass, payload_com=tuple(v.payload_com),
        winch_coulomb=v.winch_coulomb, winch_viscous=v.winch_viscous,
        motor_inertia=v.motor_inertia, tension_noise=v.tension_noise,
        tension_bias=tuple(bias) if any(bias) else None, torque_noise=v.torque_noise,
        pose_noise=v.pose_noise, timestep=v.timestep or min(0.002, 1.0 / rate), seed=v.seed)


class CdprSimNode(PlantNode):
    def __init__(self):
        super().__init__("cable_sim_node", start_parameter_services=False)  # smaller wait set
        v = self.declare_params(PARAMETERS)
        self.description = load_description(v.description or default_description_path())
        c = self.description.cdpr
        if c is None:
            raise CablelabError("cable_sim_node --plant cdpr: the description has no cdpr section")
        self.n = len(c.cables)
        truth = truth_from_parameters(self.get_name(), v, self.n, v.rate)
        self.rate = v.rate
        self.real_time = v.real_time
        self.publish_reference = v.publish_reference
        self.publish_pose = v.publish_pose
        self.speed = v.trajectory_speed
        self.settle = v.settle
        self.duration = v.duration
        self.extras_every = v.extras_every
        self.mass_change = v.mass_change
        self.mass_change_time = v.mass_change_time
        # real time: the reference two steps ahead goes out right after the state (off the
        # state -> command critical path; the consumers look it up by stamp, and a controller
        # prepares the reference terms of the next stamp while the plant steps)
        lead = v.reference_lead
        self.reference_lead = (2.0 / self.rate if self.real_time else 0.0) if lead < 0 else lead
        self._ref_sent = None
        self.start_gate()
        self.command_timeout = v.command_timeout
        self.lockstep_timeout = v.lockstep_timeout
        start = pick_and_place(np.array([0.0])).position[0]
        check_pulley_radius(c.exit_points, c.anchor_points, start[None], None, c.pulley_radius,
                            c.swivel_axes, f"{self.get_name()}: description cdpr.pulley_radius")
        self.sim = CdprSim(self.description, truth, start)
        self.nstep = max(1, int(round(1.0 / (self.rate * self.sim.truth.timestep))))
        # winch brakes: lock each motor angle where it was when the commands stopped, holding the
        # last torque that carried the load (stiff PD about the locked angle)
        self.brakes = WinchBrakes(self.sim)
        self.u = None
        self.commands = 0           # good commands received
        self.commands_at_pub = 0    # ... when the last state was published (lock-step)
        self.u_stamp = None         # stamp of the state the last command answers, if it says
        self.fallbacks = 0
        self.fallbacks_running = 0  # ... after the first command (not the start-up wait)
        self.slack_steps = 0
        # real-time misses (what bench/bench_realtime.py sums as missed cycles): steps run one or
        # more periods after they were due, steps dropped when too far behind, and steps that had
        # to apply a command answering an older state (the controller did not answer in time)
        self.late_steps = 0
        self.dropped_steps = 0
        self.stale_command_steps = 0
        self.missed_steps = 0       # steps with any of: late, braked, stale command (each once)
        self.command_age = [0, 0, 0]   # steps whose command answers the state 1, 2, >= 3 periods back
        self.latency = []           # wall time of one step (physics + publishing), s
        self.k = 0
        self.done = False
        # the robot is switched on hanging on its locked winch brakes at A: settle that first, so
        # the first published state already carries the load (sim time restarts at 0)
        for _ in range(int(round(0.5 / self.sim.truth.timestep))):
            self.sim.step(self.brake(), 1)
        self.sim.data.time = 0.0
        self.brakes.release()
        self.inputs.add("effort_commands", timeout=self.command_timeout, length=self.n)
        self._last_pub_wall = time.monotonic()
        self._wall0 = None          # wall time of sim time 0 (real-time mode)

        q, pq = stream_qos(), publisher_qos()
        self.pub_js = self.create_publisher(JointState, "/cdpr/joint_states", pq)
        self.pub_ten = self.create_publisher(JointState, "/cdpr/cable_tensions", pq)
        self.pub_pose = self.create_publisher(PoseStamped, "/cdpr/platform_pose", pq)
        self.pub_ref = self.create_publisher(MultiDOFJointTrajectory, "/cdpr/reference", pq)
        self.pub_tpose = self.create_publisher(PoseStamped, "/cdpr/ground_truth/pose", pq)
        self.pub_tpay = self.create_publisher(InertiaStamped, "/cdpr/ground_truth/payload", pq)
        self.pub_clock = self.create_publisher(Clock, "/clock", publisher_qos())
        self.publish_description(self.description)
        if not self.real_time and v.rt_priority > 0:
            self.get_logger().warning("rt_priority ignored: lock-step mode runs as fast as possible")
        self.use_fast_executor()
        self._templates()
        # real time: the commands wait queued until the step that applies them takes the newest
        # (one wake-up per step, the timer's; a keep-last-1 queue, so one take); lock-step: a
        # command wakes the node (it is the trigger)
        cmd = self.create_subscription(Float64MultiArray, "/cdpr/effort_commands", self.on_command,
                                       stream_qos(1) if self.real_time else q, raw=True)
        self.polled = [cmd] if self.real_time else []
        for sub in self.polled:
            poll(self, sub)
        self.start_diagnostics()
        self.timer = self.create_timer(1.0 / self.rate if self.real_time else 0.0002, self.tick)
        start_markers(self, "/cdpr/markers", self._marker_frame, lambda: self.sim.time,
                      v.markers_rate)
        self.publish_state()

    def _marker_frame(self):
        """The 3D view: the platform at its true pose, the cables coloured by their true tension."""
        from ..markers import cdpr_markers
        from ....rotations import quat_to_matrix

        p, q = self.sim.truth_pose()
        return cdpr_markers(self.description, p, quat_to_matrix(q), self.sim.truth_state()["tension"])


    def _templates(self) -> None:
        """Pre-serialised messages (fixed names and lengths): each step patches the numbers."""
        z, z3 = np.zeros(self.n), np.zeros(3)
        self.t_js = RawTemplate(convert.joint_state_msg(0.0, [f"winch_{i}" for i in range(1, self.n + 1)],
                                                        z, z, z))
        self.t_ten = RawTemplate(convert.joint_state_msg(0.0, [f"cable_{i}" for i in range(1, self.n + 1)],
                                                         z, None, z))
        self.t_ref = RawTemplate(convert.multidof_msg(0.0, z3, [0.0, 0.0, 0.0, 1.0], z3, None, z3, None))
        self.t_clock = RawTemplate(convert.clock_msg(0.0))
        self.t_pose = RawTemplate(convert.pose_msg(0.0, z3, [0.0, 0.0, 0.0, 1.0]))
        self.t_tpose = RawTemplate(convert.pose_msg(0.0, z3, [0.0, 0.0, 0.0, 1.0]))
        self.t_tpay = RawTemplate(convert.inertia_msg(0.0, 0.0, z3))
        self.t_tpay["inertia.m"][0] = self.sim.truth.total_mass
        self.t_tpay.vector("inertia.com")[:] = self.sim.truth.total_com
        r = self.t_ref
        self._ref_views = (r.vector("points[0].transforms[0].translation"),
                           r.vector("points[0].velocities[0].linear"),
                           r.vector("points[0].accelerations[0].linear"))

    # ------------------------------------------------------------------ callbacks
    def extend_status(self, level, msg, values):
        st = self.sim.truth_state()
        slack = [str(i + 1) for i in np.flatnonzero(st["slack"])]
        values.update({"sim time s": f"{self.sim.time:.3f}", "brake (fallback) steps": str(self.fallbacks),
                       "brake steps after the first command": str(self.fallbacks_running),
                       "slack cable steps": str(self.slack_steps), "mode": "real time" if self.real_time
                       else "as fast as possible (lock-step)",
                       "late steps": str(self.late_steps), "dropped steps": str(self.dropped_steps),
                       "stale command steps": str(self.stale_command_steps),
                       "missed steps": str(self.missed_steps),
                       "command age 1/2/3+ periods": "/".join(str(a) for a in self.command_age)})
        if self.latency:
            values["latency p99 ms"] = f"{1000 * np.percentile(np.asarray(self.latency[-1000:]), 99):.3f}"
        if slack:
            level = max(level, WARN)
            extra = "slack cable(s) " + ", ".join(slack)
            msg = extra if msg == "ok" else f"{msg}; {extra}"
        return level, msg, values

    def on_command(self, msg: Float64MultiArray) -> None:
        """An effort command (Float64MultiArray or its serialised bytes: the subscription takes
        bytes, decoded by :func:`~cablelab.ros.rawmsg.command_arrays`)."""
        try:
            values, stamp = rawmsg.command_arrays(msg)
        except ValueError:
            values, stamp = None, None          # not a command: rejected and counted below
        if self.inputs.accept("effort_commands", values, time.monotonic()):
            self.u = values.copy()
            self.commands += 1
            self.u_stamp = stamp

    def reference(self, t: float):
        """Desired pose/twist/acceleration of the s-curve at sim time t (held at A while
        settling, at A after the return): :class:`~cablelab.plants.cdpr.trajectory.ReferenceTable`."""
        if getattr(self, "_ref_table", None) is None:
            self._ref_table = ReferenceTable(self.rate, self.settle, self.speed)
        return self._ref_table.at(t)

    def tick(self) -> None:
        """Timer: lock-step, one step when answered; real time, as many steps as the wall clock
        says are due (catching up after a late timer, at most 20 at once)."""
        if self.k == 0 and self.wait_subs:
            if self.waiting_for_subscribers(self.pub_js, self._last_pub_wall, self.publish_state):
                return
            self.publish_state()
        if not self.real_time:
            self.step_once()
            return
        for sub in self.polled:
            take_newest(sub)
        now = time.monotonic()
        if self._wall0 is None:
            self._wall0 = now - self.k / self.rate
        due = int((now - self._wall0) * self.rate) - self.k
        if self.commands and due > 1:
            self.late_steps += min(due, 20) - 1        # ran at least one period after they were due
        if due > 19:                                   # far behind: do not try to catch up forever
            if self.commands:
                self.dropped_steps += due - 20
            self._wall0 = now - self.k / self.rate
            due = 20
        for i in range(max(0, due)):
            self.step_once(late=i > 0)       # the first is on time (within its period), the rest late
            if self.done:
                return

    def step_once(self, late: bool = False) -> None:
        t0 = time.perf_counter()
        missed = late
        now = time.monotonic()
        if not self.real_time:
            if self.u_stamp is not None:      # the controller says which state it answers
                answered = abs(self.u_stamp - self.sim.time) < 1e-6
            else:
                answered = self.commands > self.commands_at_pub
            if not answered and now - self._last_pub_wall < self.lockstep_timeout:
                return                                  # lock-step: wait for the controller
            fresh = answered and self.u is not None     # an answer is fresh however late it came
        else:
            fresh = self.u is not None and self.inputs.fresh("effort_commands", now)
        if not fresh:
            for _ in range(self.nstep):        # brakes act continuously: every physics step
                self.sim.step(self.brake(), 1)
            self.fallbacks += 1
            if self.commands:
                self.fallbacks_running += 1
                missed = True
        else:
            self.brakes.release()
            if self.real_time and self.u_stamp is not None:
                age = int(round((self.sim.time - self.u_stamp) * self.rate))   # 0: the last state
                self.command_age[min(max(age, 0), 2)] += 1
                if age > 0:
                    self.stale_command_steps += 1       # the answer to the last state is not here
                    missed = True
            self.sim.step(self.u, self.nstep)
        self.k += 1
        if self.mass_change and 0 <= self.mass_change_time <= self.sim.time:
            self.sim.add_mass(self.mass_change)
            self.t_tpay["inertia.m"][0] = self.sim.truth.total_mass
            self.t_tpay.vector("inertia.com")[:] = self.sim.truth.total_com
            self.get_logger().info(f"{self.mass_change:g} kg put on the platform at t = {self.sim.time:.3f} s")
            self.mass_change = 0.0
        if missed and self.commands and self.real_time:
            self.missed_steps += 1
        if self.sim.slack().any():
            self.slack_steps += 1
        self.publish_state()
        self.latency.append(time.perf_counter() - t0)
        if len(self.latency) > 100000:
            del self.latency[:50000]
        if self.duration and self.sim.time >= self.duration:
            self.done = True

    def brake(self) -> np.ndarray:
        """Torques of the locked winch brakes (the plant's own safety behaviour)."""
        return self.brakes.torque(self.u)

    def publish_state(self) -> None:
        """One sample of every output topic, from the pre-serialised templates (same bytes as
        the convert.* messages, built without an rclpy message object per sample)."""
        sim, t = self.sim, self.sim.time
        ms = sim.measure()
        extra = self.k % self.extras_every == 0          # /clock, pose and truth: maybe decimated
        lead = self.reference_lead
        if self.publish_reference and not lead:
            self._publish_reference(t)                 # before the state of its stamp
        elif self.publish_reference and self._ref_sent is None:
            for i in range(int(round(lead * self.rate))):   # start: every stamp up to the lead
                self._publish_reference(t + i / self.rate)
        js = self.t_js
        js.stamp(t)
        js["position"][:] = ms["motor_angle"]
        js["velocity"][:] = ms["motor_velocity"]
        js["effort"][:] = ms["motor_torque"]
        self.pub_js.publish(js.data())
        ten = self.t_ten
        ten.stamp(t)
        ten["position"][:] = ms["cable_length"]
        ten["effort"][:] = ms["tension"]
        self.pub_ten.publish(ten.data())
        if self.publish_reference and lead:
            self._publish_reference(t + lead)          # ahead: waits for the next state
        if extra:                                      # after the state: off the controller's path
            self.t_clock.stamp(t, "clock")
            self.pub_clock.publish(self.t_clock.data())
            if self.publish_pose:
                self._pose(self.t_pose, t, ms["position"], ms["quat"])
                self.pub_pose.publish(self.t_pose.data())
            tp, tq = sim.truth_pose()
            self._pose(self.t_tpose, t, tp, tq)
            self.pub_tpose.publish(self.t_tpose.data())
            self.t_tpay.stamp(t)
            self.pub_tpay.publish(self.t_tpay.data())
        self._last_pub_wall = time.monotonic()
        self.commands_at_pub = self.commands

    def _publish_reference(self, t: float) -> None:
        pos, vel, acc = self.reference(t)
        tr, tv, ta = self._ref_views
        tr[:], tv[:], ta[:] = pos, vel, acc
        self.t_ref.stamp(t)
        self.pub_ref.publish(self.t_ref.data())
        self._ref_sent = t

    @staticmethod
    def _pose(tpl: RawTemplate, t: float, position, quat_wxyz) -> None:
        tpl.stamp(t)
        tpl.vector("pose.position")[:] = position
        tpl.vector("pose.orientation", "xyzw")[:] = wxyz_to_xyzw(quat_wxyz)


def make_node(args) -> PlantNode:
    return CdprSimNode()
