"""CDPR controller node: PD on motor angles + mass feedforward (PDFF, 001 Fig. 6, eq. 14-15).

Each ``/cdpr/joint_states`` sample gives one ``/cdpr/effort_commands`` (motor torques, N m, order
winch_1..n) from :class:`cablelab.plants.cdpr.live.LiveController`: motor-angle PD with the
inverse geometric model of the reference ``/cdpr/reference``, feedforward of 001 eq. 14 with the
live ``/cdpr/payload_estimate`` (``feedforward`` true, PDFF) or none (PD), friction compensation
(eq. 15) and a minimum-tension floor. A stale or implausible estimate falls back to the nominal
mass (WARN on /diagnostics). Each command carries the stamp of the state it answers in
``layout.dim[0].label`` (``winch stamp=<s>``, optional; a lock-step simulator matches it). Without a reference (or with a bad motor state) nothing is
published (the simulator's brakes hold) and /diagnostics says why.

ROS parameters: :data:`PARAMETERS` (``pd_feedforward --plant cdpr --help``). Commands go out as pre-serialised messages
(:class:`cablelab.ros.rawmsg.CommandTemplate`).
"""
from __future__ import annotations

import time

import numpy as np
from geometry_msgs.msg import InertiaStamped
from sensor_msgs.msg import JointState
from std_msgs.msg import Float64MultiArray
from trajectory_msgs.msg import MultiDOFJointTrajectory

from .. import topics
from ..control import PdffConfig
from ..live import ControllerConfig, LiveController
from ....ros import convert
from ....rotations import xyzw_to_wxyz
from ....ros.inputs import ERROR, WARN
from ....ros.fastspin import drain, poll
from ....stamped import StampedBuffer
from ....ros.params import DESCRIPTION, Param, executor_params, merge
from ....ros.plant_node import PlantNode
from ....ros.qos import publisher_qos, stream_qos
from ....ros import rawmsg
from ....ros.rawmsg import CommandTemplate, RawReader


_D = PdffConfig()
PARAMETERS = merge((
    Param("description", "", "plant description: YAML file or text (empty = the first valid "
          "/plant_description)"),
    Param("feedforward", True, "mass feedforward of 001 eq. 14 with the live payload estimate "
          "(PDFF; false: PD)"),
    Param("nominal_mass", 0.0, "mass used without a valid estimate (0 = the description's "
          "platform_mass)", "kg", ge=0.0, le=1e5),
    Param("kp", _D.kp, "proportional gain on the motor angles", "N m/rad", ge=0.0, le=1e4),
    Param("kd", _D.kd, "derivative gain on the motor rates", "N m s/rad", ge=0.0, le=1e3),
    Param("coulomb", 0.3, "Coulomb friction compensation F_c (001 eq. 15)", "N m", ge=0.0, le=1e3),
    Param("viscous", 0.002, "viscous friction compensation F_v (001 eq. 15)", "N m s/rad", ge=0.0, le=1e3),
    Param("min_tension", _D.min_tension, "floor on the commanded tensions (cables stay taut)", "N",
          ge=0.0, le=1e6),
    Param("preload", _D.preload, "uniform tension the feedforward distribution stays nearest to", "N",
          ge=0.0, le=1e6),
    Param("max_torque", _D.max_torque, "saturation of the motor torques", "N m", gt=0.0, le=1e5),
    Param("model", "II", "dynamic model of the feedforward: II (with the platform's inertia) or I",
          choices=("II", "I")),
    Param("estimate_timeout", 2.0, "a payload estimate older than this (in stamps) falls back to the "
          "nominal mass", "s", gt=0.0),
    Param("reference_timeout", 0.5, "a reference older than this is stale (nothing published)",
          "s wall", gt=0.0),
    Param("state_timeout", 0.5, "a joint state older than this is stale", "s wall", gt=0.0),
    Param("sync_wait", 0.005, "a state waits this long for the reference of its stamp before the "
          "latest one is used", "s wall", ge=0.0, le=1.0),
    Param("reference_bag", "", "a reference bag written by `cablelab excite`: played from the first "
          "joint state on and published on /cdpr/reference (run the simulator with "
          "publish_reference:=false)"),
    Param("estimate_wait", 0.0, "a state waits this long for the estimate of its stamp (0 = never: "
          "use the latest; with a lock-step simulator: one deterministic chain)", "s wall",
          ge=0.0, le=10.0),
), executor_params(True))


class CdprController(PlantNode):
    def __init__(self):
        super().__init__("pd_feedforward", start_parameter_services=False)  # smaller wait set
        v = self.declare_params(PARAMETERS)
        self.gains = PdffConfig(kp=v.kp, kd=v.kd, coulomb=v.coulomb, viscous=v.viscous,
                                min_tension=v.min_tension, preload=v.preload, max_torque=v.max_torque)
        self.feedforward = v.feedforward
        self.nominal = v.nominal_mass
        self.model = v.model
        self.estimate_timeout = v.estimate_timeout
        self.controller = None
        self.refs = StampedBuffer()     # the reference may run ahead of the states
        self.sent = 0
        self.skipped = 0
        self.estimates_rejected = 0
        self.last_problem = ""
        self.last_skip = -1e9     # wall time of the last skipped sample
        self.latency = []
        self.inputs.add("joint_states", timeout=v.state_timeout)
        self.inputs.add("reference", timeout=v.reference_timeout)
        self.inputs.add("payload_estimate", timeout=self.estimate_timeout, length=1,
                        required=False)
        q = stream_qos(1000)     # deep queue: a busy moment delays samples instead of dropping them
        self.pub_cmd = self.create_publisher(Float64MultiArray, topics.EFFORT_COMMANDS, publisher_qos())
        self.keep_first_description = True   # the first valid description configures the law
        self.listen_for_description(v.description)
        # the 1 kHz inputs arrive as bytes, decoded without rclpy message objects (RawReader)
        self.readers = {"state": RawReader(JointState), "reference": RawReader(MultiDOFJointTrajectory)}
        ref_sub = self.create_subscription(MultiDOFJointTrajectory, topics.REFERENCE, self.on_reference, q, raw=True)
        est_sub = self.create_subscription(InertiaStamped, topics.PAYLOAD_ESTIMATE, self.on_estimate, q)
        self.create_subscription(JointState, topics.JOINT_STATES, self.on_state, q, raw=True)
        self.play, self.play_t0 = None, None
        if v.reference_bag:     # the designed reference, published for each state's stamp
            from ....excite import read_reference

            self.play = read_reference(v.reference_bag, topics.REFERENCE, ("x", "y", "z"))
            self.pub_ref = self.create_publisher(MultiDOFJointTrajectory, topics.REFERENCE, publisher_qos())
        self.pending = None
        self.prepared = None        # LiveController.ReferenceTerms of the next stamp (prepare_next)
        self.prepared_used = 0      # commands whose reference terms were prepared ahead
        self.sync_wait = v.sync_wait
        self.estimate_wait = v.estimate_wait
        # only a state wakes the node: the reference (published before the state of its stamp)
        # and the estimate wait queued until a state or the timer takes them (one wake-up per
        # cycle at 1 kHz instead of three); an awaited estimate (estimate_wait) still wakes it
        self.polled = [ref_sub] if self.estimate_wait > 0 and self.feedforward else [ref_sub, est_sub]
        for sub in self.polled:
            poll(self, sub)
        self.est_stamp = None       # newest estimate stamp received (valid or not)
        self.create_timer(0.002, self.on_timer)
        self.use_fast_executor()
        self._cmd = CommandTemplate("winch")     # pre-serialised commands naming their state's stamp
        self.start_diagnostics()

    def set_description(self, desc) -> None:
        if desc.cdpr is None:
            self.last_problem = "plant description has no cdpr section"
            return
        super().set_description(desc)
        nominal = self.nominal or desc.cdpr.platform_mass or 366.0
        cfg = ControllerConfig(feedforward=self.feedforward, nominal_mass=nominal,
                               estimate_timeout=self.estimate_timeout, gains=self.gains,
                               model=self.model)
        self.controller = LiveController(desc.cdpr, desc.gravity, cfg)
        self.inputs.set_length("joint_states", len(desc.cdpr.cables))

    def on_reference(self, msg: MultiDOFJointTrajectory) -> None:
        """A reference sample (MultiDOFJointTrajectory or its serialised bytes)."""
        try:
            r = rawmsg.multidof_arrays(msg, self.readers["reference"])   # position None when empty
        except ValueError:
            self.inputs.accept("reference", None, time.monotonic())     # not a message: rejected
            return
        if self.inputs.accept("reference", r["position"], time.monotonic()):
            self.refs.push(r["t"], (r["position"], xyzw_to_wxyz(r["quaternion"]),
                                    r["linear_velocity"], r["linear_acceleration"]))
            self.try_command()

    def on_estimate(self, msg: InertiaStamped) -> None:
        t, m, com = convert.inertia_arrays(msg)
        self.est_stamp = t if self.est_stamp is None else max(self.est_stamp, t)
        if not self.inputs.accept("payload_estimate", [m], time.monotonic()):
            self.try_command()
            return
        if self.controller is not None:
            if self.controller.estimate(t, m, com[:2]):
                self.prepared = None        # prepared with the previous mass: prepare anew
            else:
                self.estimates_rejected += 1
        self.try_command()                  # a state may have been waiting for this estimate

    def on_state(self, msg: JointState) -> None:
        """Keep the state (JointState or its serialised bytes); command now if the reference of
        its stamp is here (else a little later, see :meth:`on_timer`: DDS does not order samples
        across topics).

        The state -> command path is kept short: when the reference terms of this stamp were
        prepared after the previous command (:meth:`prepare_next`), the command is the motor-state
        part of the law only, and the queued reference and estimate are taken afterwards."""
        try:
            state = rawmsg.joint_state_arrays(msg, self.readers["state"])
        except ValueError:
            state = (float("nan"), [], None, None, None)      # rejected by command()
        if self.play is not None and np.isfinite(state[0]):
            self.play_t0 = state[0] if self.play_t0 is None else self.play_t0
            p, v, a = (x[0] for x in self.play(state[0] - self.play_t0))
            self.pub_ref.publish(convert.multidof_msg(state[0], p, [0.0, 0.0, 0.0, 1.0], v, None, a, None))
        if self.pending is not None or self._prepared_for(state[0]) is None:
            drain(*self.polled)         # the reference and estimate that came before it
        self.pending = (state, time.monotonic())
        self.try_command()
        self.prepare_next(state[0])

    def prepare_next(self, t: float) -> None:
        """Take the queued reference and estimate and prepare the reference terms of the next
        stamp after ``t`` (:meth:`LiveController.prepare`), off the state -> command path. Not
        with ``estimate_wait`` (a state waits for the estimate of its own stamp, which is not here
        yet when the terms would be prepared)."""
        drain(*self.polled)
        if self.controller is None or self.estimate_wait > 0 or not np.isfinite(t):
            return
        nxt = self.refs.after(t)
        if nxt is None or self._prepared_for(nxt[0]) is not None:
            return
        stamp, (pos, quat, vel, acc) = nxt
        self.prepared = self.controller.prepare(stamp, pos, quat, vel, acc)

    def _prepared_for(self, t: float):
        """The reference terms prepared ahead if they are those of stamp ``t``, else None."""
        ref = self.prepared
        return ref if ref is not None and abs(ref.t - t) <= 1e-9 else None

    def _waiting_for(self, t: float) -> tuple[bool, bool]:
        """(reference of stamp t not here yet, estimate of stamp t awaited and not here yet)."""
        ref = bool(self.refs) and self.refs.newest < t - 1e-9
        est = (self.estimate_wait > 0 and self.feedforward
               and (self.est_stamp is None or self.est_stamp < t - 1e-9))
        return ref, est

    def try_command(self, force: bool = False) -> None:
        if self.pending is None:
            return
        state, _ = self.pending
        if not force and any(self._waiting_for(state[0])):
            return                  # the reference (or awaited estimate) of this stamp is on its way
        self.pending = None
        self.command(state)

    def on_timer(self) -> None:
        drain(*self.polled)
        if self.pending is None:
            return
        age = time.monotonic() - self.pending[1]
        ref, est = self._waiting_for(self.pending[0][0])
        if (ref and age > self.sync_wait) or (not ref and est and age > self.estimate_wait) \
                or (not ref and not est):
            self.try_command(force=True)

    def command(self, state) -> None:
        """One command for ``state`` = (t, names, position, velocity, effort)."""
        t0 = time.perf_counter()
        t, _names, q, qd, _eff = state
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
        if not self.refs or not self.inputs.fresh("reference", time.monotonic()):
            self.skipped += 1
            self.last_skip = time.monotonic()
            self.last_problem = "no fresh reference: not commanding (brakes hold)"
            return
        stamp, (pos, quat, vel, acc) = self.refs.at(t)
        ref = self._prepared_for(t) if abs(stamp - t) <= 1e-9 else None
        if ref is None:
            ref = self.controller.prepare(t, pos, quat, vel, acc)       # not prepared ahead
        else:
            self.prepared_used += 1
        tau = None if ref is None else self.controller.law(ref, q, qd)
        if tau is None:
            self.skipped += 1
            self.last_skip = time.monotonic()
            self.last_problem = self.controller.status[-1][1]
            return
        # optional: the stamp of the state this command answers (a lock-step simulator matches it)
        self.pub_cmd.publish(self._cmd.data(tau, t))
        self.sent += 1
        self.latency.append(time.perf_counter() - t0)
        if len(self.latency) > 100000:
            del self.latency[:50000]

    def extend_status(self, level, msg, values):
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
                       "commands prepared ahead": str(self.prepared_used),
                       "feedforward mass kg": "-" if ctl is None or ctl.mass is None else f"{ctl.mass:.1f}"})
        if self.latency:
            values["latency p99 ms"] = f"{1000 * np.percentile(np.asarray(self.latency[-1000:]), 99):.3f}"
        return level, msg, values


def make_node() -> PlantNode:
    return CdprController()
