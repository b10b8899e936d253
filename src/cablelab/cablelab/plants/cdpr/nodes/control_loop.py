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

Parameters (``control_loop --plant cdpr --help``): the loop's, ``hardware``, and those of
``pd_feedforward`` and ``cable_sim_node --plant cdpr`` it shares. ``hardware``: ``sim`` (the
MuJoCo CAROCA, :class:`~cablelab.plants.cdpr.hardware.SimulatedCdpr`), ``stub``
(:class:`cablelab.hardware.DriverStub`, which stops with what a driver must implement) or
``package.module:Class`` (your driver, built as ``Class(joint_names, description)``).
"""
from __future__ import annotations

from geometry_msgs.msg import InertiaStamped

from ....description import load_description
from ....errors import CablelabError
from ....hardware import DriverStub, load_hardware_class
from ....sample_ring import StateLayout
from ....ros import convert
from ....ros.control_loop import LOOP_PARAMETERS, ControlLoopNode
from ....ros.fastspin import take_newest
from ....ros.params import Param, executor_params, merge, pick
from ....ros.qos import stream_qos
from .. import topics
from ..hardware import SimulatedCdpr
from ..live import LiveController
from ..loop import ReferenceLaw
from ..sim import default_description_path, truth_from_parameters
from ..streams import controller_config
from ..trajectory import ReferenceTable
from .parameters import CONTROLLER, SIM
from .outputs import CdprOutputs

__all__ = ["CdprControlLoop", "make_node", "PARAMETERS"]


PARAMETERS = merge(
    LOOP_PARAMETERS,
    (Param("hardware", "sim", "the winches: sim (the MuJoCo CAROCA), stub (a driver stub that says "
           "what a driver must implement) or package.module:Class (your driver)"),),
    pick(CONTROLLER, "feedforward", "nominal_mass", "kp", "kd", "coulomb", "viscous",
        "min_tension", "preload", "max_torque", "model", "estimate_timeout"),
    pick(SIM, "trajectory_speed", "settle", "description", "payload_mass", "payload_com",
        "pulleys", "winch_coulomb", "winch_viscous", "motor_inertia", "tension_noise", "tension_bias",
        "torque_noise", "pose_noise", "timestep", "seed", "extras_every"),
    executor_params(True))


class CdprCyclePublisher:
    """The loop's topics of one period: reference, joint states, tensions, effort command, and
    every ``extras_every`` periods /clock, the measured pose and the ground truth (the
    simulator's). Built in the loop's process or in its publisher process
    (:mod:`cablelab.ros.loop_publisher`) from a JSON ``config``: ``n`` winches, ``rate``,
    ``settle`` and ``trajectory_speed`` (the reference, recomputed from the state's stamp),
    ``extras_every``, ``payload`` ([true moving mass, CoM] of a simulated robot, else None)."""

    def __init__(self, node, config: dict):
        self.n, self.extras_every = int(config["n"]), int(config["extras_every"])
        self.reference = ReferenceTable(config["rate"], config["settle"], config["trajectory_speed"])
        self.simulated = config.get("payload") is not None
        self.out = CdprOutputs(node, self.n, truth=self.simulated, commands=True)
        if self.simulated:                  # the true moving mass and CoM do not change
            self.out.payload(*config["payload"])

    @classmethod
    def layout(cls, config: dict) -> StateLayout:
        """The records of the publisher process: the state, the command and the extras published."""
        n = int(config["n"])
        extras = [("tension", n), ("cable_length", n), ("position", 3), ("quat", 4)]
        if config.get("payload") is not None:
            extras += [("true_position", 3), ("true_quat", 4)]
        return StateLayout(n, tuple(extras), n)

    def publish(self, state, command, cycle: int) -> None:
        t, extra, out = state.t, state.extra, self.out
        out.reference(t, *self.reference.at(t))       # the reference of the state's stamp, before it
        out.joints(t, state.position, state.velocity, state.effort)
        if "tension" in extra:
            out.tensions(t, extra["tension"], extra.get("cable_length"))
        if command is not None:
            out.command(t, command)
        if cycle % self.extras_every == 0:
            pose = (extra["position"], extra["quat"]) if "position" in extra and "quat" in extra else None
            # the truth read with the state (not now: another thread or process publishes)
            truth = (extra["true_position"], extra["true_quat"]) if self.simulated else None
            out.extras(t, pose, truth)


class CdprControlLoop(ControlLoopNode):
    def __init__(self):
        super().__init__("control_loop")
        v = self.v = self.declare_params(PARAMETERS)
        desc = load_description(v.description or default_description_path())
        c = desc.cdpr
        if c is None:
            raise CablelabError("control_loop --plant cdpr: the description has no cdpr section")
        self.n = len(c.cables)
        self.reference = ReferenceTable(self.rate, v.settle, v.trajectory_speed)
        self.law = ReferenceLaw(LiveController(c, desc.gravity, controller_config(v, c.platform_mass)),
                                self.reference.at, self.reference.rows, self.rate)
        self.extras_every = v.extras_every
        self.hardware = hardware = self._hardware(v.hardware, desc)
        self.simulated = isinstance(hardware, SimulatedCdpr)
        self.estimates_rejected = 0

        self.publish_description(desc)
        # the estimate waits in a keep-last-1 queue that no executor watches; the loop takes it
        # after a write (take_inputs), never waiting for it
        self.inputs.add("payload_estimate", timeout=v.estimate_timeout, length=1, required=False)
        self.est_sub = self.create_subscription(InertiaStamped, topics.PAYLOAD_ESTIMATE, self.on_estimate,
                                                stream_qos(1))
        self.setup_loop(hardware, self.law)

    def _hardware(self, spec: str, desc):
        names = [f"winch_{i}" for i in range(1, self.n + 1)]
        if spec == "sim":
            truth = truth_from_parameters(self.get_name(), self.v, self.n, self.rate)
            return SimulatedCdpr(desc, truth, self.rate, self.reference.at(0.0)[0])
        cls = DriverStub if spec == "stub" else load_hardware_class(spec)
        return cls(names, desc)

    # ------------------------------------------------------------------ the loop's hooks
    def cycle_publisher(self):
        truth = self.hardware.sim.truth if self.simulated else None
        return CdprCyclePublisher, {
            "n": self.n, "rate": self.rate, "settle": self.v.settle, "trajectory_speed": self.v.trajectory_speed,
            "extras_every": self.extras_every,
            "payload": None if truth is None else [float(truth.total_mass), [float(x) for x in truth.total_com]]}

    def take_inputs(self) -> None:
        take_newest(self.est_sub)

    def on_estimate(self, msg: InertiaStamped) -> None:
        t, m, com = convert.inertia_arrays(msg)
        if not self.accept("payload_estimate", [m]):
            return
        if not self.law.estimate(t, m, com[:2]):
            self.estimates_rejected += 1

    def after_cycle(self, state) -> None:
        self.law.prepare_next(state.t + 1.0 / self.rate, spare=not self.loop.behind())

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


def make_node() -> CdprControlLoop:
    return CdprControlLoop()
