"""CDPR payload estimator node: mass and CoM (x_G, y_G) per sample (001 eq. 12-13), live.

Each tension sample, ``/cdpr/cable_tensions`` (dynamometers) or ``/cdpr/joint_states`` (motor
torques, friction compensated, 001 eq. 15), at the pose of its stamp, ``/cdpr/reference``
(desired, 001's real-time choice) or ``/cdpr/platform_pose`` (measured), gives one
``/cdpr/payload_estimate`` stamped like it (pre-serialised InertiaStamped: m = total moving mass,
com = (x_G, y_G, NaN), frame ``platform``). Matching by stamp and counting:
:class:`cablelab.plants.cdpr.streams.EstimateStream`; the law: :class:`cablelab.plants.cdpr.live.
LiveEstimator`. Bad input (NaN, wrong length, negative tension, ill-conditioned W, stale pose)
publishes nothing and is reported on /diagnostics, slack cables as WARN. Parameters:
:data:`.parameters.ESTIMATOR`.
"""
from __future__ import annotations

import time

from geometry_msgs.msg import InertiaStamped, PoseStamped
from sensor_msgs.msg import JointState
from trajectory_msgs.msg import MultiDOFJointTrajectory

from .. import topics
from ..streams import EstimateStream, estimator_config
from ....ros import convert
from ....ros.plant_node import PlantNode
from ....ros.qos import publisher_qos, stream_qos
from ....rotations import xyzw_to_wxyz
from .outputs import estimate_template, fill_estimate
from .parameters import ESTIMATOR as PARAMETERS


class CdprPayloadEstimator(PlantNode):
    def __init__(self):
        super().__init__("payload_estimator", start_parameter_services=False)  # smaller wait set
        v = self.declare_params(PARAMETERS)
        self.config = estimator_config(v)
        self.stream = EstimateStream(self.config, batch=v.poll_period > 0)
        self.published, self.t_est = 0, estimate_template()
        self.motor = motor = self.config.tensions == "motor"
        batch = self.stream.batch
        for name in ("tensions", "pose") + (("joint_states",) if motor else ()):
            self.inputs.add(name, timeout=v.input_timeout)
        self.pub = self.create_publisher(InertiaStamped, topics.PAYLOAD_ESTIMATE, publisher_qos())
        self.listen_for_description(v.description, keep_first=True)     # it configures the law
        # deep queues: a busy moment delays samples instead of dropping them. Batch mode: the
        # inputs wake nobody; every poll_period s a timer estimates the newest tension sample, the
        # only one a keep-last-1 queue keeps (never decoded in Python), with the poses around it
        q_pose, q_tension = (stream_qos(4), stream_qos(1)) if batch else (stream_qos(1000), stream_qos(1000))
        # the pose first: when both wait in one wake-up, a tension sample meets the pose of its
        # stamp (FastExecutor and rclpy's executor take ready topics in creation order)
        if self.config.pose == "desired":
            self.subscribe(MultiDOFJointTrajectory, topics.REFERENCE, self.on_reference, q_pose, raw=True,
                           polled=batch)
        else:
            self.subscribe(PoseStamped, topics.PLATFORM_POSE, self.on_pose, q_pose, polled=batch)
        self.subscribe(JointState, topics.JOINT_STATES if motor else topics.CABLE_TENSIONS, self.on_tensions,
                       q_tension, raw=True, polled=batch)
        if batch:
            self.create_timer(v.poll_period, self.on_poll)
        self.use_fast_executor()
        self.start_diagnostics()

    def set_description(self, desc) -> None:
        self.stream.describe(desc.cdpr, desc.gravity)
        if desc.cdpr is not None:
            super().set_description(desc)
            for name in self.inputs.inputs.keys() & {"tensions", "joint_states"}:
                self.inputs.set_length(name, len(desc.cdpr.cables))

    def on_reference(self, msg: MultiDOFJointTrajectory) -> None:
        """A reference sample (MultiDOFJointTrajectory or its serialised bytes)."""
        r = self.decode_raw("pose", MultiDOFJointTrajectory, msg)
        if r is not None and self.accept("pose", r["position"]):       # (position None when empty)
            self.stream.pose(r["t"], r["position"], xyzw_to_wxyz(r["quaternion"]), r["linear_acceleration"])

    def on_pose(self, msg: PoseStamped) -> None:
        t, pos, q = convert.pose_arrays(msg)
        if self.accept("pose", pos):
            self.stream.pose(t, pos, xyzw_to_wxyz(q))

    def on_tensions(self, msg: JointState) -> None:
        """A tension sample (JointState or its serialised bytes): the dynamometers' (each one
        estimated; the stream says why not) or the motor state's (``tensions: motor``)."""
        name = "joint_states" if self.motor else "tensions"
        js = self.decode_raw(name, JointState, msg)
        if js is not None and not self.motor:
            self.accept(name, js[4])
            self.estimate(js[0], js[4])
        elif js is not None and self.accept(name, js[4]) and js[3] is not None:
            self.estimate(js[0], motor=(js[3], js[4]))

    def estimate(self, t: float, tensions=None, motor=None) -> None:
        """One sample: estimated and published at once (batch: kept for :meth:`on_poll`)."""
        t0 = time.perf_counter()
        self.publish_estimate(self.stream.sample(t, tensions, motor), t0)

    def on_poll(self) -> None:
        """Batch mode: take every queued sample (each one checked by the input monitor), estimate
        the newest and publish it."""
        self.take_polled()
        t0 = time.perf_counter()
        self.publish_estimate(self.stream.poll(), t0)

    def publish_estimate(self, est, t0: float) -> None:
        if est is not None:
            self.pub.publish(fill_estimate(self.t_est, *est).data())
            self.published += 1
            self.latency.since(t0)

    def extend_status(self, level, msg, values):
        values["published"] = str(self.published)
        return self.stream.report(level, msg, values)


def make_node() -> PlantNode:
    return CdprPayloadEstimator()
