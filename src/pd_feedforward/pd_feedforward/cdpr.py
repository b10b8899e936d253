"""CDPR controller node: PD on motor angles + mass feedforward (PDFF, 001 Fig. 6, eq. 14-15).

Each ``/cdpr/joint_states`` sample gives one ``/cdpr/effort_commands`` (motor torques, N m, order
winch_1..n) from :class:`cablelab.plants.cdpr_live.LiveController`: motor-angle PD with the
inverse geometric model of the reference ``/cdpr/reference``, feedforward of 001 eq. 14 with the
live ``/cdpr/payload_estimate`` (``feedforward`` true, PDFF) or none (PD), friction compensation
(eq. 15) and a minimum-tension floor. A stale or implausible estimate falls back to the nominal
mass (WARN on /diagnostics). Each command carries the stamp of the state it answers in
``layout.dim[0].label`` (``winch stamp=<s>``, optional; a lock-step simulator matches it). Without a reference (or with a bad motor state) nothing is
published (the simulator's brakes hold) and /diagnostics says why.

ROS parameters: ``description``, ``feedforward`` (bool), ``nominal_mass`` (kg, 0 = the
description's platform_mass), ``kp`` (N m/rad), ``kd`` (N m s/rad), ``coulomb``, ``viscous``
(friction compensation), ``min_tension`` (N), ``preload`` (N), ``max_torque`` (N m), ``model``
("II" | "I"), ``estimate_timeout`` (s of stamps), ``reference_timeout``, ``state_timeout`` (s wall),
``sync_wait`` (s wall a state waits for the reference of its stamp before the latest one is used).
"""
from __future__ import annotations

import time

import numpy as np
from geometry_msgs.msg import InertiaStamped
from rclpy.node import Node
from sensor_msgs.msg import JointState
from std_msgs.msg import Float64MultiArray, MultiArrayDimension, String
from trajectory_msgs.msg import MultiDOFJointTrajectory

from cablelab.description import load_description
from cablelab.errors import CablelabError
from cablelab.plants.cdpr_control import PdffConfig
from cablelab.plants.cdpr_live import ControllerConfig, LiveController
from cablelab.ros import convert
from cablelab.ros.diagnostics import Diagnostics
from cablelab.ros.inputs import ERROR, WARN, InputMonitor
from cablelab.ros.qos import DESCRIPTION_QOS, stream_qos


class CdprController(Node):
    def __init__(self):
        super().__init__("pd_feedforward", start_parameter_services=False)  # smaller wait set
        p = self.declare_parameter
        d = PdffConfig()
        self.gains = PdffConfig(kp=float(p("kp", d.kp).value), kd=float(p("kd", d.kd).value),
                                coulomb=float(p("coulomb", 0.3).value),
                                viscous=float(p("viscous", 0.002).value),
                                min_tension=float(p("min_tension", d.min_tension).value),
                                preload=float(p("preload", d.preload).value),
                                max_torque=float(p("max_torque", d.max_torque).value))
        self.feedforward = bool(p("feedforward", True).value)
        self.nominal = float(p("nominal_mass", 0.0).value)
        self.model = str(p("model", "II").value)
        if self.model not in ("I", "II"):
            raise CablelabError("pd_feedforward: parameter model must be I or II")
        self.estimate_timeout = float(p("estimate_timeout", 2.0).value)
        self.controller = None
        self.ref = None
        self.sent = 0
        self.skipped = 0
        self.estimates_rejected = 0
        self.last_problem = ""
        self.last_skip = -1e9     # wall time of the last skipped sample
        self.latency = []
        self.inputs = InputMonitor()
        self.inputs.add("joint_states", timeout=float(p("state_timeout", 0.5).value))
        self.inputs.add("reference", timeout=float(p("reference_timeout", 0.5).value))
        self.inputs.add("payload_estimate", timeout=self.estimate_timeout, length=1,
                        required=False)
        q = stream_qos(1000)     # deep queue: a busy moment delays samples instead of dropping them
        self.pub_cmd = self.create_publisher(Float64MultiArray, "/cdpr/effort_commands", q)
        self.create_subscription(String, "/plant_description", self.on_description, DESCRIPTION_QOS)
        text = p("description", "").value
        if text:
            self.set_description(load_description(text))
        self.create_subscription(MultiDOFJointTrajectory, "/cdpr/reference", self.on_reference, q)
        self.create_subscription(InertiaStamped, "/cdpr/payload_estimate", self.on_estimate, q)
        self.create_subscription(JointState, "/cdpr/joint_states", self.on_state, q)
        self.pending = None
        self.sync_wait = float(p("sync_wait", 0.005).value)
        self.create_timer(0.002, self.on_timer)
        self.diag = Diagnostics(self, update=self.status)

    def set_description(self, desc) -> None:
        if desc.cdpr is None:
            self.last_problem = "plant description has no cdpr section"
            return
        nominal = self.nominal or desc.cdpr.platform_mass or 366.0
        cfg = ControllerConfig(feedforward=self.feedforward, nominal_mass=nominal,
                               estimate_timeout=self.estimate_timeout, gains=self.gains,
                               model=self.model)
        self.controller = LiveController(desc.cdpr, desc.gravity, cfg)
        self.inputs.set_length("joint_states", len(desc.cdpr.cables))

    def on_description(self, msg: String) -> None:
        if self.controller is None:
            try:
                self.set_description(load_description(msg.data))
            except CablelabError as exc:
                self.last_problem = f"bad /plant_description: {exc}"

    def on_reference(self, msg: MultiDOFJointTrajectory) -> None:
        d = convert.multidof_arrays(msg)
        if self.inputs.accept("reference", d["position"], time.monotonic()):
            q = d["quaternion"]
            self.ref = (d["t"], d["position"], None if q is None else q[[3, 0, 1, 2]],
                        d["linear_velocity"], d["linear_acceleration"])
            self.try_command()

    def on_estimate(self, msg: InertiaStamped) -> None:
        t, m, com = convert.inertia_arrays(msg)
        if not self.inputs.accept("payload_estimate", [m], time.monotonic()):
            return
        if self.controller is not None and not self.controller.estimate(t, m, com[:2]):
            self.estimates_rejected += 1

    def on_state(self, msg: JointState) -> None:
        """Keep the state; command now if the reference of its stamp is here (else a little later,
        see :meth:`on_timer`: DDS does not order samples across topics)."""
        self.pending = (msg, time.monotonic())
        self.try_command()

    def try_command(self, force: bool = False) -> None:
        if self.pending is None:
            return
        msg, _ = self.pending
        t = convert.from_stamp(msg.header.stamp)
        if not force and self.ref is not None and self.ref[0] < t - 1e-9:
            return                          # the reference of this stamp is probably on its way
        self.pending = None
        self.command(msg)

    def on_timer(self) -> None:
        if self.pending is not None and time.monotonic() - self.pending[1] > self.sync_wait:
            self.try_command(force=True)

    def command(self, msg: JointState) -> None:
        t0 = time.perf_counter()
        t, _names, q, qd, _eff = convert.joint_state_arrays(msg)
        if self.controller is None:
            self.skipped += 1
            self.last_skip = time.monotonic()
            self.last_problem = "waiting for /plant_description"
            return
        if not self.inputs.accept("joint_states", q, time.monotonic()) or qd is None or qd.size != q.size:
            self.skipped += 1
            self.last_skip = time.monotonic()
            self.last_problem = "bad motor state (NaN, empty or wrong length)"
            return
        if self.ref is None or not self.inputs.fresh("reference", time.monotonic()):
            self.skipped += 1
            self.last_skip = time.monotonic()
            self.last_problem = "no fresh reference: not commanding (brakes hold)"
            return
        _, pos, quat, vel, acc = self.ref
        tau = self.controller.update(t, q, qd, pos, quat, vel, acc)
        if tau is None:
            self.skipped += 1
            self.last_skip = time.monotonic()
            self.last_problem = self.controller.status[-1][1]
            return
        cmd = convert.float_array_msg(tau)
        # optional: the stamp of the state this command answers (a lock-step simulator matches it)
        cmd.layout.dim = [MultiArrayDimension(label=f"winch stamp={t:.9f}", size=len(tau), stride=len(tau))]
        self.pub_cmd.publish(cmd)
        self.sent += 1
        self.latency.append(time.perf_counter() - t0)
        if len(self.latency) > 100000:
            del self.latency[:50000]

    def status(self):
        level, msg, values = self.inputs.status(time.monotonic())
        ctl = self.controller
        if ctl is None:
            level, msg = ERROR, self.last_problem or "waiting for /plant_description"
        elif ctl.status and ctl.status[-1][0] > 0:
            level = max(level, ctl.status[-1][0])
            msg = ctl.status[-1][1] if msg == "ok" else f"{msg}; {ctl.status[-1][1]}"
        if time.monotonic() - self.last_skip < 2.0 and self.last_problem:
            level = max(level, WARN)
            msg = self.last_problem if msg == "ok" else f"{msg}; {self.last_problem}"
        values.update({"mode": "PDFF" if self.feedforward else "PD", "commands": str(self.sent),
                       "skipped": str(self.skipped), "estimates rejected": str(self.estimates_rejected),
                       "feedforward mass kg": "-" if ctl is None or ctl.mass is None else f"{ctl.mass:.1f}"})
        if self.latency:
            values["latency p99 ms"] = f"{1000 * np.percentile(np.asarray(self.latency[-1000:]), 99):.3f}"
        return level, msg, values


def make_node(args) -> Node:
    return CdprController()
