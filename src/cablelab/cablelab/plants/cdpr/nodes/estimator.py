"""CDPR payload estimator node: mass and CoM (x_G, y_G) per sample (001 eq. 12-13), live.

Inputs: ``/cdpr/cable_tensions`` (dynamometers) or ``/cdpr/joint_states`` (motor torques,
friction compensated, 001 eq. 15), and the pose for the wrench matrix: ``/cdpr/reference``
(desired, 001's real-time choice) or ``/cdpr/platform_pose`` (measured). The description comes
from the ``description`` parameter or ``/plant_description``. Each tension sample gives one
``/cdpr/payload_estimate`` (InertiaStamped, m = total moving mass, com = (x_G, y_G, NaN), frame
``platform``) stamped like it, computed by :class:`cablelab.plants.cdpr.live.LiveEstimator`.
Bad input (NaN, wrong length, negative tension, ill-conditioned W, stale pose) publishes nothing
and is reported on /diagnostics; slack cables are reported as WARN.

ROS parameters: :data:`PARAMETERS` (``payload_estimator --plant cdpr --help``). The estimate goes out as a pre-serialised message
(:class:`cablelab.ros.rawmsg.RawTemplate`); only the topic the ``tensions`` source needs is
subscribed (``/cdpr/cable_tensions`` or ``/cdpr/joint_states``).
"""
from __future__ import annotations

import time

import numpy as np
from geometry_msgs.msg import InertiaStamped, PoseStamped
from sensor_msgs.msg import JointState
from trajectory_msgs.msg import MultiDOFJointTrajectory

from ..live import EstimatorConfig, LiveEstimator
from ....ros import convert
from ....rotations import xyzw_to_wxyz
from ....ros.inputs import ERROR, WARN
from ....ros.fastspin import drain, poll
from ....stamped import StampedBuffer
from ....ros.params import Param, executor_params, merge
from ....ros.plant_node import PlantNode
from ....ros.qos import publisher_qos, stream_qos
from ....ros import rawmsg
from ....ros.rawmsg import RawReader, RawTemplate


PARAMETERS = merge((
    Param("description", "", "plant description: YAML file or text (empty = the first valid "
          "/plant_description)"),
    Param("model", "II", "dynamic model: II (with the platform's inertia terms, 001 eq. 13) or I",
          choices=("II", "I")),
    Param("tensions", "dynamometer", "tension source: the dynamometers (/cdpr/cable_tensions) or "
          "the motor torques, friction compensated (/cdpr/joint_states)",
          choices=("dynamometer", "motor")),
    Param("pose", "desired", "pose of the wrench matrix: the reference (desired, 001's real-time "
          "choice) or /cdpr/platform_pose (measured)", choices=("desired", "measured")),
    Param("platform_inertia", False, "include the platform's own inertia terms"),
    Param("coulomb", 0.0, "Coulomb friction compensation of the motor torques", "N m", ge=0.0, le=1e3),
    Param("viscous", 0.0, "viscous friction compensation of the motor torques", "N m s/rad",
          ge=0.0, le=1e3),
    Param("pulley_radius", 0.0, "pulley radius of the model (0 = the description's)", "m",
          ge=0.0, le=10.0),
    Param("stale_after", 0.5, "largest stamp difference between a tension sample and its pose", "s",
          gt=0.0),
    Param("input_timeout", 0.5, "an input older than this is stale", "s wall", gt=0.0),
    Param("poll_period", 0.0, "0: every input sample gives one estimate; > 0: batch mode, the newest "
          "tension sample estimated every poll_period s (a 1/poll_period Hz estimator on the 1 kHz "
          "stream)", "s", ge=0.0, le=0.1),
), executor_params(True))


class CdprPayloadEstimator(PlantNode):
    def __init__(self):
        super().__init__("payload_estimator", start_parameter_services=False)  # smaller wait set
        v = self.declare_params(PARAMETERS)
        self.config = EstimatorConfig(
            model=v.model, tensions=v.tensions, pose=v.pose, platform_inertia=v.platform_inertia,
            coulomb=v.coulomb, viscous=v.viscous, stale_after=v.stale_after,
            pulley_radius=v.pulley_radius if v.pulley_radius > 0 else None)
        timeout = v.input_timeout
        self.estimator = None
        self.poses = StampedBuffer()    # t -> (position, quat wxyz, acceleration); may run ahead
        self.motor = None       # (t, velocity, effort)
        self.published = 0
        self.skipped = 0
        self.last_problem = ""
        self.last_skip = -1e9     # wall time of the last skipped sample
        self.latency = []       # processing times, s (for the benchmark)
        self.readers = {"joints": RawReader(JointState), "reference": RawReader(MultiDOFJointTrajectory)}
        self.inputs.add("tensions", timeout=timeout)
        self.inputs.add("pose", timeout=timeout)
        if self.config.tensions == "motor":
            self.inputs.add("joint_states", timeout=timeout)
        q = stream_qos(1000)     # deep queue: a busy moment delays samples instead of dropping them
        self.pub = self.create_publisher(InertiaStamped, "/cdpr/payload_estimate", publisher_qos())
        self.keep_first_description = True   # the first valid description configures the law
        self.listen_for_description(v.description)
        # batch mode: the inputs wake nobody; a timer takes what queued every poll_period s and
        # estimates the newest tension sample, one estimate per period. The tension queue keeps
        # only that newest sample (keep-last 1: the samples in between are overwritten inside
        # DDS, never decoded in Python) and the pose queue the stamps around it (the newest
        # tension's and a reference lead of two periods)
        self.poll_period = v.poll_period
        q_pose, q_tension = (stream_qos(4), stream_qos(1)) if self.poll_period > 0 else (q, q)
        # the pose first: when both wait in one wake-up, a tension sample meets the pose of its
        # stamp (FastExecutor and rclpy's executor take ready topics in creation order)
        if self.config.pose == "desired":
            subs = [self.create_subscription(MultiDOFJointTrajectory, "/cdpr/reference", self.on_reference,
                                             q_pose, raw=True)]
        else:
            subs = [self.create_subscription(PoseStamped, "/cdpr/platform_pose", self.on_pose, q_pose)]
        if self.config.tensions == "motor":        # (1 kHz of traffic nobody reads otherwise)
            subs.append(self.create_subscription(JointState, "/cdpr/joint_states", self.on_joints, q_tension,
                                                 raw=True))
        else:
            subs.append(self.create_subscription(JointState, "/cdpr/cable_tensions", self.on_tensions, q_tension,
                                                 raw=True))
        self.newest = None          # (t, m, com) not published yet (batch mode)
        self.batch_newest = None    # (t, tensions) of the newest input sample of the period (batch mode)
        if self.poll_period > 0:
            for sub in subs:
                poll(self, sub)
            self.polled = subs
            self.create_timer(self.poll_period, self.on_poll)
        self.use_fast_executor()
        self.t_est = RawTemplate(convert.inertia_msg(0.0, 0.0, [0.0, 0.0, float("nan")]))
        self._est_m, self._est_com = self.t_est["inertia.m"], self.t_est.vector("inertia.com")
        self.start_diagnostics()

    # ------------------------------------------------------------------ inputs
    def set_description(self, desc) -> None:
        if desc.cdpr is None:
            self.last_problem = "plant description has no cdpr section"
            return
        super().set_description(desc)
        self.estimator = LiveEstimator(desc.cdpr, desc.gravity, self.config)
        n = len(desc.cdpr.cables)
        self.inputs.set_length("tensions", n)
        if "joint_states" in self.inputs.inputs:
            self.inputs.set_length("joint_states", n)

    def on_reference(self, msg: MultiDOFJointTrajectory) -> None:
        """A reference sample (MultiDOFJointTrajectory or its serialised bytes)."""
        try:
            r = rawmsg.multidof_arrays(msg, self.readers["reference"])   # position None when empty
        except ValueError:
            self.inputs.accept("pose", None, time.monotonic())          # not a message: rejected
            return
        if self.inputs.accept("pose", r["position"], time.monotonic()):
            self.poses.push(r["t"], (r["position"], xyzw_to_wxyz(r["quaternion"]), r["linear_acceleration"]))

    def on_pose(self, msg: PoseStamped) -> None:
        t, pos, q = convert.pose_arrays(msg)
        if self.inputs.accept("pose", pos, time.monotonic()):
            self.poses.push(t, (pos, xyzw_to_wxyz(q), None))

    def _joint_state(self, msg):
        """(t, names, q, qd, effort) of a JointState or its bytes; None for bytes that are not one."""
        try:
            return rawmsg.joint_state_arrays(msg, self.readers["joints"])
        except ValueError:
            return None

    def on_joints(self, msg: JointState) -> None:
        if self.config.tensions != "motor":
            return
        js = self._joint_state(msg)
        if js is None:
            self.inputs.accept("joint_states", None, time.monotonic())
            return
        t, _names, _q, qd, eff = js
        if self.inputs.accept("joint_states", eff, time.monotonic()) and qd is not None:
            self.motor = (t, qd, eff)
            self.sample(t, None)

    def on_tensions(self, msg: JointState) -> None:
        if self.config.tensions != "dynamometer":
            return
        js = self._joint_state(msg)
        if js is None:
            self.inputs.accept("tensions", None, time.monotonic())
            return
        t, _names, _q, _qd, eff = js
        self.inputs.accept("tensions", eff, time.monotonic())
        self.sample(t, eff)

    def sample(self, t: float, tensions) -> None:
        """A new input sample: estimated at once, or in batch mode kept as the newest of the
        period (:meth:`on_poll` estimates that one: the estimate is per sample, 001 eq. 13, so
        the newest sample alone gives the estimate the period publishes)."""
        if self.poll_period > 0:
            self.batch_newest = (t, tensions)
        else:
            self.estimate(t, tensions)

    # ------------------------------------------------------------------ estimate
    def estimate(self, t: float, tensions) -> None:
        """One estimate at stamp t; nothing is published unless every check passes."""
        t0 = time.perf_counter()
        if self.estimator is None:
            self.skipped += 1
            self.last_skip = time.monotonic()
            self.last_problem = "waiting for /plant_description"
            return
        if not self.poses:
            self.skipped += 1
            self.last_skip = time.monotonic()
            self.last_problem = f"no {self.config.pose} pose yet"
            return
        tp, (pos, quat, acc) = self.poses.at(t)
        kw = {"tensions": tensions}
        times = {"pose": tp}
        if self.config.tensions == "motor":
            _, qd, eff = self.motor
            kw = {"effort": eff, "motor_velocity": qd}
        res = self.estimator.update(t, position=pos, quat=quat, acceleration=acc, input_times=times, **kw)
        if res is None:
            self.skipped += 1
            self.last_skip = time.monotonic()
            self.last_problem = self.estimator.status[-1][1]
            return
        m, com = res
        if self.poll_period > 0:
            self.newest = (t, m, com)                          # published by on_poll
        else:
            self.publish_estimate(t, m, com)
        self.latency.append(time.perf_counter() - t0)
        if len(self.latency) > 100000:
            del self.latency[:50000]

    def publish_estimate(self, t: float, m: float, com) -> None:
        self.t_est.stamp(t)                                    # pre-serialised InertiaStamped
        self._est_m[0] = m
        self._est_com[:2] = com[:2]
        self.pub.publish(self.t_est.data())
        self.published += 1

    def on_poll(self) -> None:
        """Batch mode: take every queued sample (each one checked by the input monitor), estimate
        the newest and publish it."""
        drain(*self.polled)
        if self.batch_newest is not None:
            self.estimate(*self.batch_newest)
            self.batch_newest = None
        if self.newest is not None:
            self.publish_estimate(*self.newest)
            self.newest = None

    def extend_status(self, level, msg, values):
        est_status = self.estimator.status if self.estimator is not None else [(ERROR, self.last_problem)]
        worst = max((s[0] for s in est_status), default=0)
        if worst > 0:
            level = max(level, worst)
            msg = est_status[-1][1] if msg == "ok" else f"{msg}; {est_status[-1][1]}"
        elif time.monotonic() - self.last_skip < 2.0 and self.last_problem and level == 0:
            level, msg = WARN, f"skipped samples ({self.last_problem})"
        values.update({"published": str(self.published), "skipped": str(self.skipped),
                       "last problem": self.last_problem or "none",
                       "model": self.config.model, "tensions": self.config.tensions,
                       "pose": self.config.pose})
        if self.latency:
            lat = np.asarray(self.latency[-1000:])
            values["latency p99 ms"] = f"{1000 * np.percentile(lat, 99):.3f}"
        return level, msg, values


def make_node(args) -> PlantNode:
    return CdprPayloadEstimator()
