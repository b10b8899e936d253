"""ROS 2 adapters of the leg (spec 003_leg.md sec. 5, ``/leg/*`` topics): thin shells around
:class:`~.sim.LegSim`, :class:`~.estimator.HopEstimator` and :class:`~.controller.ApexController`.

* ``sim``: steps the hybrid plant at ``rate`` (default 1 kHz) with the latest
  ``/leg/effort_commands`` torque (stale -> 0), publishes ``/leg/joint_states`` (``body``: encoder
  height, backward-difference velocity, F_in; ``motor``: theta, 0, torque), ``/leg/contact``,
  ``/leg/ground_truth/state``, ``/clock``, ``/plant_description``.
* ``estimator``: ``/leg/joint_states`` (+ ``/leg/contact`` when present) -> ``/leg/hop_estimate``;
  /diagnostics reports the phase source, chattering flips, switch/height disagreements, dropouts.
* ``controller``: ``/leg/hop_estimate`` (+ ``/leg/reference`` apex height) ->
  ``/leg/effort_commands``.

ROS parameters of each role: :data:`PARAMETERS` (``cable_sim_node --plant leg --help``, ...).
"""
from __future__ import annotations

import math
import time

import numpy as np
from sensor_msgs.msg import JointState
from std_msgs.msg import Float64MultiArray
from trajectory_msgs.msg import JointTrajectory

from ...description import load_description
from ...ros import convert
from ...ros.clock import ClockPublisher
from ...ros.params import Param
from ...ros.plant_node import PlantNode
from ...ros.qos import publisher_qos, stream_qos
from .control import ApexController
from .description import leg_of
from .estimator import HopEstimator
from .hybrid import STANCE
from .sim import LegSim

DEFAULT_DESCRIPTION_FILE = "data/leg.yaml"


_DESCRIPTION = Param("description", "", "plant description: YAML file or text (empty = the "
                     "package's data/leg.yaml)")
PARAMETERS = {
    "sim": (
        _DESCRIPTION,
        Param("mass_scale", 1.0, "true mass / the description's mass", gt=0.0, le=100.0),
        Param("preload", float("nan"), "true spring preload F_0 (NaN = the description's)", "N",
              ge=-1e5, le=1e5, nan=True),
        Param("z0_offset", 0.03, "start height above touch-down height z_td", "m", ge=0.0, le=10.0),
        Param("rate", 1000.0, "simulation and publishing rate", "Hz", ge=1.0, le=100000.0),
        Param("command_timeout", 0.5, "a torque command older than this means zero torque",
              "s wall", gt=0.0),
    ),
    "estimator": (
        _DESCRIPTION,
        Param("h", 0.5e-3, "height hysteresis of the phase detection", "m", ge=0.0, le=1.0),
        Param("f_on", 1.0, "ground reaction force above which stance starts without a contact switch",
              "N", ge=0.0, le=1e5),
    ),
    "controller": (
        _DESCRIPTION,
        Param("h_des", 0.016, "desired apex height above z_td until a /leg/reference arrives", "m",
              ge=0.0, le=10.0),
        Param("T", 1.0, "initial stance torque", "N m", ge=0.0, le=1e4),
        Param("P", 0.30, "stance torque duration", "s", gt=0.0, le=10.0),
        Param("k_i", 10.0, "integral gain on the apex-height error", "N m/m", ge=0.0, le=1e6),
        Param("k_ff", 0.5, "feedforward fraction of the model-based Newton step", ge=0.0, le=10.0),
        Param("T_max", 4.0, "largest stance torque", "N m", gt=0.0, le=1e4),
        Param("mode", "apex", "apex-height control or a constant open-loop torque",
              choices=("apex", "open_loop")),
    ),
}


def _description(text: str):
    if text:
        return load_description(text)
    from pathlib import Path

    return load_description(Path(__file__).parent / DEFAULT_DESCRIPTION_FILE)


class LegSimNode(PlantNode):
    def __init__(self):
        super().__init__("cable_sim_node")
        v = self.declare_params(PARAMETERS["sim"])
        self.description = _description(v.description)
        leg = leg_of(self.description)
        nominal = leg.params(self.description.gravity)
        truth = nominal.replace(m=nominal.m * v.mass_scale,
                                F0=nominal.F0 if math.isnan(v.preload) else v.preload)
        self.res = leg.encoder_resolution
        self.rate = v.rate
        self.sim = LegSim(truth, nominal.z_td + v.z0_offset, 0.0, dt=1.0 / self.rate)
        self.tau = 0.0
        self._z_prev = None
        self.inputs.add("effort_commands", timeout=v.command_timeout, length=1,
                        required=False)
        self.pub_js = self.create_publisher(JointState, "/leg/joint_states", publisher_qos())
        self.pub_contact = self.create_publisher(JointState, "/leg/contact", publisher_qos())
        self.pub_truth = self.create_publisher(JointState, "/leg/ground_truth/state", publisher_qos())
        self.clock = ClockPublisher(self)
        self.publish_description(self.description)
        self.create_subscription(Float64MultiArray, "/leg/effort_commands", self.on_command, stream_qos())
        self.start_diagnostics()
        self.timer = self.create_timer(1.0 / self.rate, self.tick)

    def extend_status(self, level, msg, values):
        values["sim time s"] = f"{self.sim.t:.3f}"
        values["events"] = str(len(self.sim.events))
        return level, msg or "ok", values

    def on_command(self, msg: Float64MultiArray) -> None:
        values = convert.float_array(msg)
        if self.inputs.accept("effort_commands", values, time.monotonic()):
            self.tau = float(values[0])

    def tick(self) -> None:
        if not self.inputs.fresh("effort_commands", time.monotonic()):
            self.tau = 0.0
        self.sim.step(self.tau if self.sim.phase == STANCE else 0.0)
        s = self.sim
        t, z = s.t, s.z
        zq = round(z / self.res) * self.res if self.res > 0 else z
        zd_m = 0.0 if self._z_prev is None else (zq - self._z_prev) * self.rate
        self._z_prev = zq
        L = s.p.L
        theta = math.acos(min(max(zq / (2 * L), -1.0), 1.0))
        self.clock.publish(t)
        self.pub_js.publish(convert.joint_state_msg(t, ["body", "motor"], [zq, theta], [zd_m, 0.0],
                                                    [s.f_in, self.tau]))
        self.pub_contact.publish(convert.joint_state_msg(t, ["contact"], [float(s.phase)]))
        ap = s.events[-1].t if s.events else math.nan
        self.pub_truth.publish(convert.joint_state_msg(
            t, ["height", "phase", "apex_height", "grf"], [z, float(s.phase), math.nan, 0.0],
            [s.zd, 0.0, ap, 0.0], [0.0, 0.0, 0.0, s.grf()]))


class LegEstimatorNode(PlantNode):
    def __init__(self):
        super().__init__("payload_estimator")
        v = self.declare_params(PARAMETERS["estimator"])
        self.description = _description(v.description)
        params = leg_of(self.description).params(self.description.gravity)
        self.est = HopEstimator(params, h=v.h, f_on=v.f_on)
        self.contact = None
        self.t_contact = -math.inf
        self.inputs.add("joint_states", timeout=0.5)
        self.inputs.add("contact", timeout=0.5, length=1, required=False)
        self.pub = self.create_publisher(JointState, "/leg/hop_estimate", publisher_qos())
        self.create_subscription(JointState, "/leg/joint_states", self.on_state, stream_qos())
        self.create_subscription(JointState, "/leg/contact", self.on_contact, stream_qos())
        self.start_diagnostics()

    def extend_status(self, level, msg, values):
        e = self.est
        values.update({"phase source": "height (no contact switch)" if self.contact is None else "contact switch",
                       "chattering flips": str(e.flips), "switch/height disagreements": str(e.disagreements),
                       "dropouts": str(e.dropouts)})
        if self.contact is None:
            msg = "; ".join(x for x in (msg, "no /leg/contact: phase from height") if x)
            level = max(level, 1)
        return level, msg or "ok", values

    def on_contact(self, msg: JointState) -> None:
        _, _, pos, _, _ = convert.joint_state_arrays(msg)
        if self.inputs.accept("contact", pos, time.monotonic()):
            self.contact = float(pos[0])

    def on_state(self, msg: JointState) -> None:
        t, names, pos, _, eff = convert.joint_state_arrays(msg)
        if pos is None or "body" not in names or not self.inputs.accept("joint_states", pos, time.monotonic()):
            self.est.dropouts += 1
            return
        z = float(pos[names.index("body")])
        tau = float(eff[names.index("motor")]) if eff is not None and "motor" in names and len(eff) == len(names) else None
        contact = self.contact if self.inputs.fresh("contact", time.monotonic()) else None
        e = self.est.step(t, z, contact, tau)
        self.pub.publish(convert.joint_state_msg(
            t, ["height", "phase", "apex_height", "grf"], [e.z, float(e.phase), e.apex_height, 0.0],
            [e.zd, 0.0, e.apex_time, 0.0], [0.0, 0.0, 0.0, e.grf]))


class LegControllerNode(PlantNode):
    def __init__(self):
        super().__init__("pd_feedforward")
        v = self.declare_params(PARAMETERS["controller"])
        self.description = _description(v.description)
        params = leg_of(self.description).params(self.description.gravity)
        self.ctl = ApexController(params, params.z_td + v.h_des, T=v.T, P=v.P, k_i=v.k_i, k_ff=v.k_ff,
                                  T_max=v.T_max, mode=v.mode)
        self.last_apex = math.nan
        self.inputs.add("hop_estimate", timeout=0.5)
        self.inputs.add("reference", timeout=math.inf, length=1, required=False)
        self.pub = self.create_publisher(Float64MultiArray, "/leg/effort_commands", publisher_qos())
        self.create_subscription(JointState, "/leg/hop_estimate", self.on_estimate, stream_qos())
        self.create_subscription(JointTrajectory, "/leg/reference", self.on_reference, stream_qos())
        self.start_diagnostics()

    def extend_status(self, level, msg, values):
        values.update({"T N m": f"{self.ctl.T:.4f}", "h_des m": f"{self.ctl.h_des:.4f}", "mode": self.ctl.mode})
        return level, msg or "ok", values

    def on_reference(self, msg: JointTrajectory) -> None:
        _, _, pos, _, _ = convert.joint_trajectory_point(msg)
        if pos is not None and self.inputs.accept("reference", pos, time.monotonic()):
            self.ctl.h_des = float(np.asarray(pos).ravel()[0])

    def on_estimate(self, msg: JointState) -> None:
        t, names, pos, vel, _ = convert.joint_state_arrays(msg)
        if pos is None or vel is None or "phase" not in names or not self.inputs.accept("hop_estimate", pos[[names.index("phase")]], time.monotonic()):
            return  # hold T (stale or NaN estimate)
        ia = names.index("apex_height")
        h, ta = float(pos[ia]), float(vel[ia])
        if math.isfinite(ta) and ta != self.last_apex:
            self.last_apex = ta
            self.ctl.on_apex(h)
        tau = self.ctl.torque(t, int(round(pos[names.index("phase")])))
        self.pub.publish(convert.command_msg([tau], stamp=t))


ROLES = {"sim": LegSimNode, "estimator": LegEstimatorNode, "controller": LegControllerNode}


def make_node(role: str, args=None) -> PlantNode:
    """The node of ``role`` in {"sim", "estimator", "controller"} (``cable_sim_node --plant leg``,
    ``payload_estimator --plant leg``, ``pd_feedforward --plant leg``)."""
    return ROLES[role]()
