"""CDPR simulator node: the MuJoCo CAROCA of 001 (real pulleys, friction winches;
:class:`cablelab.plants.cdpr.sim.CdprSim`) driven by ``/cdpr/effort_commands``.

Publishes (CONTRACT sec. 2) ``/cdpr/joint_states`` (winch_1..n: motor angle, rate, torque from
current), ``/cdpr/cable_tensions`` (cable_1..n: paid-out length, dynamometer tension),
``/cdpr/platform_pose`` (optional), ``/cdpr/reference`` (the pick-and-place s-curve of 001 sec.
II-C, unless ``publish_reference`` is false), the ground truth ``/cdpr/ground_truth/{pose,payload}``,
``/clock`` and ``/plant_description``, from pre-serialised templates (:mod:`cablelab.ros.rawmsg`).

When it steps and with which torques is :class:`cablelab.plants.cdpr.stepping.SimStepper`: real
time at ``rate`` Hz of wall time, or lock-step with the controller as fast as possible. Without a
fresh command the winch brakes lock the motor angles, reported as WARN on /diagnostics, as are
slack cables. Parameters: ``cable_sim_node --plant cdpr --help``.
"""
from __future__ import annotations

import time

import numpy as np
from std_msgs.msg import Float64MultiArray

from ....description import load_description
from ....errors import CablelabError
from ....ros import rawmsg
from ....ros.fastspin import poll, take_newest
from ....ros.inputs import WARN
from ....ros.markers import start_markers
from ....ros.params import DESCRIPTION, START_GATE, Param, executor_params, markers_rate, merge
from ....ros.plant_node import PlantNode
from ....ros.qos import stream_qos
from ....ros.status import Latency, add_problem
from .. import topics
from ..geometry import check_pulley_radius
from ..hardware import SimulatedCdpr
from ..markers import sim_markers
from ..sim import default_description_path, truth_from_parameters
from ..stepping import SimStepper
from ..trajectory import ReferenceTable, pick_and_place
from .outputs import CdprOutputs


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
    markers_rate("/cdpr/markers: cables coloured by tension, platform, exit points"),
    Param("seed", 0, "seed of the noise generator", ge=0),
), START_GATE, executor_params(True))


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
        self.rate, self.real_time, self.publish_pose = v.rate, v.real_time, v.publish_pose
        self.extras_every = v.extras_every
        self.start_gate()
        start = pick_and_place(np.array([0.0])).position[0]
        check_pulley_radius(c.exit_points, c.anchor_points, start[None], None, c.pulley_radius,
                            c.swivel_axes, f"{self.get_name()}: description cdpr.pulley_radius")
        self.stepper = SimStepper(
            SimulatedCdpr(self.description, truth, self.rate, start), self.rate, self.real_time,
            v.lockstep_timeout, ReferenceTable(self.rate, v.settle, v.trajectory_speed),
            v.reference_lead if v.publish_reference else None, v.duration, v.mass_change,
            v.mass_change_time, self.mass_changed)
        self.sim = self.stepper.sim
        self.latency = Latency()
        self.inputs.add("effort_commands", timeout=v.command_timeout, length=self.n)
        self.out = CdprOutputs(self, self.n, truth=True)
        self.out.payload(self.sim.truth.total_mass, self.sim.truth.total_com)
        self.publish_description(self.description)
        if not self.real_time and v.rt_priority > 0:
            self.get_logger().warning("rt_priority ignored: lock-step mode runs as fast as possible")
        self.use_fast_executor()
        # real time: the commands wait queued until the step that applies them takes the newest
        # (one wake-up per step, the timer's; a keep-last-1 queue, so one take); lock-step: a
        # command wakes the node (it is the trigger)
        cmd = self.create_subscription(Float64MultiArray, topics.EFFORT_COMMANDS, self.on_command,
                                       stream_qos(1) if self.real_time else stream_qos(), raw=True)
        self.polled = [cmd] if self.real_time else []
        for sub in self.polled:
            poll(self, sub)
        self.start_diagnostics()
        self.timer = self.create_timer(1.0 / self.rate if self.real_time else 0.0002, self.tick)
        start_markers(self, topics.MARKERS, lambda: sim_markers(self.description, self.sim),
                      lambda: self.sim.time, v.markers_rate)
        self.publish_state()

    @property
    def done(self) -> bool:
        return self.stepper.done

    def extend_status(self, level, msg, values):
        values.update(self.stepper.values())
        self.latency.report(values)
        slack = [str(i + 1) for i in np.flatnonzero(self.sim.truth_state()["slack"])]
        if slack:
            level, msg = add_problem(level, msg, WARN, "slack cable(s) " + ", ".join(slack))
        return level, msg, values

    def on_command(self, msg: Float64MultiArray) -> None:
        """An effort command (serialised bytes, :func:`~cablelab.ros.rawmsg.command_arrays`)."""
        cmd = self.decode("effort_commands", rawmsg.command_arrays, msg)
        if cmd is not None and self.accept("effort_commands", cmd[0]):
            self.stepper.command(*cmd)

    def mass_changed(self, kg: float) -> None:
        self.out.payload(self.sim.truth.total_mass, self.sim.truth.total_com)
        self.get_logger().info(f"{kg:g} kg put on the platform at t = {self.sim.time:.3f} s")

    def tick(self) -> None:
        """Timer: lock-step, one step when answered; real time, as many steps as the wall clock
        says are due (catching up after a late timer, at most 20 at once)."""
        if self.stepper.k == 0 and self.wait_subs:
            if self.waiting_for_subscribers(self.out.pub_js, self.stepper.last_publish, self.publish_state):
                return
            self.publish_state()
        if not self.real_time:
            self.step_once()
            return
        for sub in self.polled:
            take_newest(sub)
        for i in range(self.stepper.due(time.monotonic())):
            self.step_once(late=i > 0)       # the first is on time (within its period), the rest late
            if self.done:
                return

    def step_once(self, late: bool = False) -> None:
        t0 = time.perf_counter()
        now = time.monotonic()
        if self.stepper.step(now, self.inputs.fresh("effort_commands", now), late):
            self.publish_state()
            self.latency.since(t0)

    def publish_state(self) -> None:
        """One sample of every output topic (the reference of each stamp before its state, or
        ahead of it after the state; /clock, pose and truth every ``extras_every`` steps)."""
        sim, out, t = self.sim, self.out, self.sim.time
        ms = sim.measure()
        before, after = self.stepper.reference_stamps(t)
        for tr in before + [None] + after:
            if tr is None:
                out.joints(t, ms["motor_angle"], ms["motor_velocity"], ms["motor_torque"])
                out.tensions(t, ms["tension"], ms["cable_length"])
            else:
                out.reference(tr, *self.stepper.reference.at(tr))
        if self.stepper.k % self.extras_every == 0:     # after the state: off the controller's path
            out.extras(t, (ms["position"], ms["quat"]) if self.publish_pose else None, sim.truth_pose())
        self.stepper.published(time.monotonic())


def make_node() -> PlantNode:
    return CdprSimNode()
