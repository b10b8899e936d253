"""CDPR control loop: the winches (simulated, or a driver) and the PDFF law in one process on
absolute deadlines, the ros2_control way (:mod:`cablelab.ros.control_loop`).

Each period: read the winch sensors -> :class:`cablelab.plants.cdpr.loop.ReferenceLaw` (the
``pd_feedforward`` node's law, :class:`~cablelab.plants.cdpr.live.LiveController`, on the
pick-and-place reference of the ``cable_sim_node``) -> write the motor torques. After the write
it publishes what the three-process loop has on its topics: ``/cdpr/joint_states``,
``/cdpr/cable_tensions``, ``/cdpr/reference`` (the state's stamp, published before the state),
``/cdpr/effort_commands`` (naming the state's stamp), and every ``extras_every`` periods
``/clock``, ``/cdpr/platform_pose`` and, with the simulator, the ground truth
``/cdpr/ground_truth/{pose,payload}``; ``/plant_description`` at start. It takes the newest
``/cdpr/payload_estimate`` of the separate ``payload_estimator`` without waiting; without a
fresh one the feedforward uses the nominal mass and /diagnostics says so (WARN).

ROS parameters: :data:`PARAMETERS` (``control_loop --plant cdpr --help``): the loop's
(:data:`cablelab.ros.control_loop.LOOP_PARAMETERS`), ``hardware``, the controller's as
``pd_feedforward --plant cdpr``, the reference's and the simulator's as ``cable_sim_node --plant
cdpr``. ``hardware``: ``sim`` (the MuJoCo CAROCA, :class:`~cablelab.plants.cdpr.hardware.
SimulatedCdpr`), ``stub`` (:class:`cablelab.hardware.DriverStub`, which stops with what a driver
must implement) or ``package.module:Class`` (your driver, built as ``Class(joint_names,
description)``).
"""
from __future__ import annotations

import numpy as np
from geometry_msgs.msg import InertiaStamped, PoseStamped
from rosgraph_msgs.msg import Clock
from sensor_msgs.msg import JointState
from std_msgs.msg import Float64MultiArray
from trajectory_msgs.msg import MultiDOFJointTrajectory

from ....description import load_description
from ....errors import CablelabError
from ....hardware import DriverStub, load_hardware_class
from ....ros import convert
from ....ros.control_loop import LOOP_PARAMETERS, ControlLoopNode
from ....ros.params import Param, executor_params, merge
from ....ros.fastspin import take_newest
from ....ros.qos import publisher_qos, stream_qos
from ....ros.rawmsg import CommandTemplate, RawTemplate
from ....rotations import wxyz_to_xyzw
from ..control import PdffConfig
from ..hardware import SimulatedCdpr
from ..live import ControllerConfig, LiveController
from ..loop import ReferenceLaw
from ..sim import default_description_path
from ..trajectory import ReferenceTable
from . import controller as _controller
from . import sim as _sim

__all__ = ["CdprControlLoop", "make_node", "PARAMETERS"]


def _of(specs, *names):
    by = {s.name: s for s in specs}
    return tuple(by[n] for n in names)


PARAMETERS = merge(
    LOOP_PARAMETERS,
    (Param("hardware", "sim", "the winches: sim (the MuJoCo CAROCA), stub (a driver stub that says "
           "what a driver must implement) or package.module:Class (your driver)"),),
    _of(_controller.PARAMETERS, "feedforward", "nominal_mass", "kp", "kd", "coulomb", "viscous",
        "min_tension", "preload", "max_torque", "model", "estimate_timeout"),
    _of(_sim.PARAMETERS, "trajectory_speed", "settle", "description", "payload_mass", "payload_com",
        "pulleys", "winch_coulomb", "winch_viscous", "motor_inertia", "tension_noise", "tension_bias",
        "torque_noise", "pose_noise", "timestep", "seed", "extras_every"),
    executor_params(True))


class CdprControlLoop(ControlLoopNode):
    def __init__(self):
        super().__init__("control_loop")
        v = self.v = self.declare_params(PARAMETERS)
        desc = load_description(v.description or default_description_path())
        c = desc.cdpr
        if c is None:
            raise CablelabError("control_loop --plant cdpr: the description has no cdpr section")
        self.n = len(c.cables)
        gains = PdffConfig(kp=v.kp, kd=v.kd, coulomb=v.coulomb, viscous=v.viscous,
                           min_tension=v.min_tension, preload=v.preload, max_torque=v.max_torque)
        self.estimate_timeout = v.estimate_timeout
        nominal = v.nominal_mass or c.platform_mass or 366.0
        cfg = ControllerConfig(feedforward=v.feedforward, nominal_mass=nominal,
                               estimate_timeout=self.estimate_timeout, gains=gains, model=v.model)
        speed, settle = v.trajectory_speed, v.settle
        self.reference = ReferenceTable(self.rate, settle, speed)
        self.law = ReferenceLaw(LiveController(c, desc.gravity, cfg), self.reference.at)
        self.extras_every = v.extras_every
        self.hardware = hardware = self._hardware(v.hardware, desc)
        self.simulated = isinstance(hardware, SimulatedCdpr)
        self.estimates_rejected = 0

        q = publisher_qos()
        self.pub_js = self.create_publisher(JointState, "/cdpr/joint_states", q)
        self.pub_ten = self.create_publisher(JointState, "/cdpr/cable_tensions", q)
        self.pub_ref = self.create_publisher(MultiDOFJointTrajectory, "/cdpr/reference", q)
        self.pub_cmd = self.create_publisher(Float64MultiArray, "/cdpr/effort_commands", q)
        self.pub_pose = self.create_publisher(PoseStamped, "/cdpr/platform_pose", q)
        self.pub_clock = self.create_publisher(Clock, "/clock", publisher_qos())
        if self.simulated:
            self.pub_tpose = self.create_publisher(PoseStamped, "/cdpr/ground_truth/pose", q)
            self.pub_tpay = self.create_publisher(InertiaStamped, "/cdpr/ground_truth/payload", q)
        self.publish_description(desc)
        self._templates()
        # the estimate waits in a keep-last-1 queue that no executor watches; the loop takes it
        # after a write (take_inputs), never waiting for it
        self.inputs.add("payload_estimate", timeout=self.estimate_timeout, length=1, required=False)
        self.est_sub = self.create_subscription(InertiaStamped, "/cdpr/payload_estimate", self.on_estimate,
                                                stream_qos(1))
        self.setup_loop(hardware, self.law)

    def _hardware(self, spec: str, desc):
        names = [f"winch_{i}" for i in range(1, self.n + 1)]
        if spec == "sim":
            truth = _sim.truth_from_parameters(self.get_name(), self.v, self.n, self.rate)
            return SimulatedCdpr(desc, truth, self.rate, self.reference.at(0.0)[0])
        cls = DriverStub if spec == "stub" else load_hardware_class(spec)
        return cls(names, desc)

    def _templates(self) -> None:
        """Pre-serialised messages: each period patches stamps and numbers only."""
        z, z3 = np.zeros(self.n), np.zeros(3)
        self.t_js = RawTemplate(convert.joint_state_msg(0.0, [f"winch_{i}" for i in range(1, self.n + 1)], z, z, z))
        self.t_ten = RawTemplate(convert.joint_state_msg(0.0, [f"cable_{i}" for i in range(1, self.n + 1)],
                                                         z, None, z))
        self.t_ref = RawTemplate(convert.multidof_msg(0.0, z3, [0.0, 0.0, 0.0, 1.0], z3, None, z3, None))
        r = self.t_ref
        self._ref_views = (r.vector("points[0].transforms[0].translation"),
                           r.vector("points[0].velocities[0].linear"),
                           r.vector("points[0].accelerations[0].linear"))
        self.t_cmd = CommandTemplate("winch")
        self.t_clock = RawTemplate(convert.clock_msg(0.0))
        self.t_pose = RawTemplate(convert.pose_msg(0.0, z3, [0.0, 0.0, 0.0, 1.0]))
        self.t_tpose = RawTemplate(convert.pose_msg(0.0, z3, [0.0, 0.0, 0.0, 1.0]))
        self.t_tpay = RawTemplate(convert.inertia_msg(0.0, 0.0, z3))
        if self.simulated:                  # the true moving mass and CoM do not change
            self.t_tpay["inertia.m"][0] = self.hardware.sim.truth.total_mass
            self.t_tpay.vector("inertia.com")[:] = self.hardware.sim.truth.total_com

    # ------------------------------------------------------------------ the loop's hooks
    def publish_cycle(self, state, command) -> None:
        t = state.t
        ref = self.t_ref                        # the reference of the state's stamp, before it
        for view, value in zip(self._ref_views, self.reference.at(t)):
            view[:] = value
        ref.stamp(t)
        self.pub_ref.publish(ref.data())
        js = self.t_js
        js.stamp(t)
        js["position"][:] = state.position
        js["velocity"][:] = state.velocity
        js["effort"][:] = state.effort
        self.pub_js.publish(js.data())
        extra = state.extra
        if "tension" in extra:
            ten = self.t_ten
            ten.stamp(t)
            ten["effort"][:] = extra["tension"]
            if "cable_length" in extra:
                ten["position"][:] = extra["cable_length"]
            self.pub_ten.publish(ten.data())
        if command is not None:
            self.pub_cmd.publish(self.t_cmd.data(command, t))
        if self._cycle % self.extras_every == 0:
            self.t_clock.stamp(t, "clock")
            self.pub_clock.publish(self.t_clock.data())
            if "position" in extra and "quat" in extra:
                self._pose(self.t_pose, t, extra["position"], extra["quat"])
                self.pub_pose.publish(self.t_pose.data())
            if self.simulated:          # the truth read with the state (not now: another thread may publish)
                self._pose(self.t_tpose, t, extra["true_position"], extra["true_quat"])
                self.pub_tpose.publish(self.t_tpose.data())
                self.t_tpay.stamp(t)
                self.pub_tpay.publish(self.t_tpay.data())

    def take_inputs(self) -> None:
        take_newest(self.est_sub)

    def on_estimate(self, msg: InertiaStamped) -> None:
        import time

        t, m, com = convert.inertia_arrays(msg)
        if not self.inputs.accept("payload_estimate", [m], time.monotonic()):
            return
        if not self.law.estimate(t, m, com[:2]):
            self.estimates_rejected += 1

    def after_cycle(self, state) -> None:
        self.law.prepare_next(state.t + 1.0 / self.rate)

    def extend_status(self, level, msg, values):
        level, msg, values = super().extend_status(level, msg, values)
        ctl = self.law.controller
        values.update({"mode": "PDFF" if ctl.config.feedforward else "PD",
                       "hardware": type(self.hardware).__name__,
                       "estimates rejected": str(self.estimates_rejected),
                       "commands prepared ahead": str(self.law.prepared_used),
                       "feedforward mass kg": "-" if ctl.mass is None else f"{ctl.mass:.1f}"})
        if self.simulated:
            values["sim time s"] = f"{self.hardware.sim.time:.3f}"
            values["brake steps"] = str(self.hardware.braked)
        return level, msg, values

    @staticmethod
    def _pose(tpl: RawTemplate, t: float, position, quat_wxyz) -> None:
        tpl.stamp(t)
        tpl.vector("pose.position")[:] = position
        tpl.vector("pose.orientation", "xyzw")[:] = wxyz_to_xyzw(quat_wxyz)


def make_node(args) -> CdprControlLoop:
    return CdprControlLoop()
