"""CDPR payload estimator node: mass and CoM (x_G, y_G) per sample (001 eq. 12-13), live.

Inputs: ``/cdpr/cable_tensions`` (dynamometers) or ``/cdpr/joint_states`` (motor torques,
friction compensated, 001 eq. 15), only the one the ``tensions`` source needs, and the pose of
the wrench matrix: ``/cdpr/reference`` (desired, 001's real-time choice) or
``/cdpr/platform_pose`` (measured); the description from ``description`` or ``/plant_description``.
Each tension sample gives one ``/cdpr/payload_estimate`` (pre-serialised InertiaStamped, m = total
moving mass, com = (x_G, y_G, NaN), frame ``platform``) stamped like it: matching and counting in
:class:`cablelab.plants.cdpr.streams.EstimateStream`, the law :class:`cablelab.plants.cdpr.live.LiveEstimator`.
Bad input (NaN, wrong length, negative tension, ill-conditioned W, stale pose) publishes nothing
and is reported on /diagnostics; slack cables as WARN. Parameters: ``payload_estimator --plant cdpr --help``.
"""
from __future__ import annotations

import time
from functools import partial

from geometry_msgs.msg import InertiaStamped, PoseStamped
from sensor_msgs.msg import JointState
from trajectory_msgs.msg import MultiDOFJointTrajectory

from .. import topics
from ..streams import EstimateStream, estimator_config
from ....ros import convert, rawmsg
from ....ros.fastspin import drain, poll
from ....ros.params import Param, executor_params, merge
from ....ros.plant_node import PlantNode
from ....ros.qos import publisher_qos, stream_qos
from ....ros.rawmsg import RawReader, RawTemplate
from ....ros.status import Latency
from ....rotations import xyzw_to_wxyz


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
        self.config = estimator_config(v)
        # batch mode (poll_period > 0): the inputs wake nobody; a timer takes what queued every
        # poll_period s and estimates the newest tension sample, one estimate per period. The
        # tension queue keeps only that newest sample (keep-last 1: the samples in between are
        # overwritten inside DDS, never decoded in Python) and the pose queue the stamps around
        # it (the newest tension's and a reference lead of two periods)
        self.stream = EstimateStream(self.config, batch=v.poll_period > 0)
        self.published = 0
        self.latency = Latency()
        motor = self.config.tensions == "motor"
        for name in ("tensions", "pose") + (("joint_states",) if motor else ()):
            self.inputs.add(name, timeout=v.input_timeout)
        self.pub = self.create_publisher(InertiaStamped, topics.PAYLOAD_ESTIMATE, publisher_qos())
        self.keep_first_description = True   # the first valid description configures the law
        self.listen_for_description(v.description)
        q = stream_qos(1000)     # deep queue: a busy moment delays samples instead of dropping them
        q_pose, q_tension = (stream_qos(4), stream_qos(1)) if self.stream.batch else (q, q)
        # the pose first: when both wait in one wake-up, a tension sample meets the pose of its
        # stamp (FastExecutor and rclpy's executor take ready topics in creation order)
        sub = self.create_subscription
        subs = [sub(MultiDOFJointTrajectory, topics.REFERENCE, self.on_reference, q_pose, raw=True)
                if self.config.pose == "desired" else sub(PoseStamped, topics.PLATFORM_POSE, self.on_pose, q_pose)]
        subs.append(sub(JointState, topics.JOINT_STATES, self.on_joints, q_tension, raw=True) if motor else
                    sub(JointState, topics.CABLE_TENSIONS, self.on_tensions, q_tension, raw=True))
        self.polled = subs if self.stream.batch else []      # (1 kHz of traffic nobody reads otherwise)
        for s in self.polled:
            poll(self, s)
        if self.stream.batch:
            self.create_timer(v.poll_period, self.on_poll)
        self.use_fast_executor()
        self.t_est = RawTemplate(convert.inertia_msg(0.0, 0.0, [0.0, 0.0, float("nan")]))
        self.readers = {"joints": RawReader(JointState), "reference": RawReader(MultiDOFJointTrajectory)}
        self.start_diagnostics()

    def set_description(self, desc) -> None:
        self.stream.describe(desc.cdpr, desc.gravity)
        if desc.cdpr is not None:
            super().set_description(desc)
            for name in ("tensions", "joint_states"):
                if name in self.inputs.inputs:
                    self.inputs.set_length(name, len(desc.cdpr.cables))

    def on_reference(self, msg: MultiDOFJointTrajectory) -> None:
        """A reference sample (MultiDOFJointTrajectory or its serialised bytes)."""
        r = self.decode("pose", partial(rawmsg.multidof_arrays, reader=self.readers["reference"]), msg)
        if r is not None and self.accept("pose", r["position"]):       # (position None when empty)
            self.stream.pose(r["t"], r["position"], xyzw_to_wxyz(r["quaternion"]), r["linear_acceleration"])

    def on_pose(self, msg: PoseStamped) -> None:
        t, pos, q = convert.pose_arrays(msg)
        if self.accept("pose", pos):
            self.stream.pose(t, pos, xyzw_to_wxyz(q))

    def _joint_state(self, name: str, msg):
        return self.decode(name, partial(rawmsg.joint_state_arrays, reader=self.readers["joints"]), msg)

    def on_joints(self, msg: JointState) -> None:
        if self.config.tensions != "motor":
            return
        js = self._joint_state("joint_states", msg)
        if js is not None and self.accept("joint_states", js[4]) and js[3] is not None:
            self.estimate(js[0], motor=(js[3], js[4]))

    def on_tensions(self, msg: JointState) -> None:
        if self.config.tensions != "dynamometer":
            return
        js = self._joint_state("tensions", msg)
        if js is not None:
            self.accept("tensions", js[4])
            self.estimate(js[0], js[4])

    def estimate(self, t: float, tensions=None, motor=None) -> None:
        """One sample: estimated and published at once (batch: kept for :meth:`on_poll`)."""
        t0 = time.perf_counter()
        self.publish_estimate(self.stream.sample(t, tensions, motor), t0)

    def on_poll(self) -> None:
        """Batch mode: take every queued sample (each one checked by the input monitor), estimate
        the newest and publish it."""
        drain(*self.polled)
        t0 = time.perf_counter()
        self.publish_estimate(self.stream.poll(), t0)

    def publish_estimate(self, est, t0: float) -> None:
        if est is None:
            return
        t, m, com = est
        self.t_est.stamp(t)                                    # pre-serialised InertiaStamped
        self.t_est["inertia.m"][0] = m
        self.t_est.vector("inertia.com")[:2] = com[:2]
        self.pub.publish(self.t_est.data())
        self.published += 1
        self.latency.since(t0)

    def extend_status(self, level, msg, values):
        values["published"] = str(self.published)
        level, msg, values = self.stream.report(level, msg, values)
        return level, msg, self.latency.report(values)

def make_node() -> PlantNode:
    return CdprPayloadEstimator()
