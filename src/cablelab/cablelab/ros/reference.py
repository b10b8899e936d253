"""A reference a controller node plays itself and publishes on the plant's reference topic.

A controller that does not follow a reference topic plays one: a bag written by ``cablelab
excite`` (the ``reference_bag`` parameter, :func:`reference_bag_param`) or a built-in trajectory.
Time starts at the first joint state; each sample is published (``trajectory_msgs/
JointTrajectory``, stamped like the state it goes with) so recordings hold what was played::

    self.player = ReferencePlayer.from_bag(self, v.reference_bag, topics.REFERENCE, JOINTS)
    ...
    q_ref, qd_ref, qdd_ref = self.player(t, q)      # in the joint-state callback
"""
from __future__ import annotations

import time
from typing import Callable, Sequence

import numpy as np
from trajectory_msgs.msg import JointTrajectory, MultiDOFJointTrajectory

from . import convert
from .params import Param
from .qos import publisher_qos, stream_qos

__all__ = ["ReferencePlayer", "reference_bag_param", "FollowedReference"]


def reference_bag_param(topic: str, overrides: str = "reference_source") -> Param:
    """The controllers' ``reference_bag`` parameter (played reference published on ``topic``)."""
    return Param("reference_bag", "", "a reference bag written by `cablelab excite`: played from the "
                 f"first joint state on and published on {topic} (overrides {overrides})")


class ReferencePlayer:
    """Plays ``trajectory(t, q0) -> (q, qd, qdd)`` ((N, n) each at times ``t`` (N,) s from the
    first state, ``q0`` the first state's positions) and publishes each played sample.

    Args:
        node: the controller node (creates the publisher).
        topic: the plant's reference topic.
        joints: the joint names of the published trajectory point.
        platform: the reference is the platform's position x, y, z, published as a
            ``MultiDOFJointTrajectory`` (orientation identity; the CDPR) instead.
        absolute: ``trajectory`` is given the state stamps themselves, not the time since the
            first state.
    """

    def __init__(self, node, topic: str, joints: Sequence[str],
                 trajectory: Callable[[np.ndarray, np.ndarray], tuple], platform: bool = False,
                 absolute: bool = False):
        self.joints, self.trajectory, self.platform = list(joints), trajectory, platform
        self.absolute = absolute
        self.pub = node.create_publisher(MultiDOFJointTrajectory if platform else JointTrajectory, topic,
                                         publisher_qos())
        self.t0 = None
        self.q0 = None

    @classmethod
    def from_bag(cls, node, path: str, topic: str, joints: Sequence[str],
                 platform: bool = False) -> "ReferencePlayer":
        """The reference in the bag at ``path`` (:func:`cablelab.excite.read_reference`)."""
        from ..excite import read_reference

        play = read_reference(path, topic, joints)
        return cls(node, topic, joints, lambda t, _q0: play(t), platform)

    def __call__(self, t: float, q) -> tuple:
        """The reference (q, qd, qdd) (n,) each at state stamp ``t`` (s) of a state at ``q``;
        published stamped ``t``."""
        if self.t0 is None:
            self.t0, self.q0 = t, np.array(q, dtype=float)
        ref = tuple(x[0] for x in self.trajectory(np.array([t if self.absolute else t - self.t0]), self.q0))
        if self.platform:
            p, v, a = ref
            self.pub.publish(convert.multidof_msg(t, p, [0.0, 0.0, 0.0, 1.0], v, None, a, None))
        else:
            self.pub.publish(convert.joint_trajectory_msg(t, self.joints, *ref))
        return ref


class FollowedReference:
    """The reference a controller follows: played by the controller itself (the bag of a
    ``reference_bag`` parameter, else a built-in ``trajectory``; :class:`ReferencePlayer`,
    published on ``topic``) or the latest point received on ``topic`` (input ``reference`` of
    the node: wrong names, length, NaN rejected and counted; stale after ``timeout`` s wall).

    Args:
        node: the controller (:class:`~cablelab.ros.plant_node.PlantNode`).
        topic: the plant's reference topic; joints: its joint names.
        bag: a reference bag path (empty: none); trajectory: the built-in reference
            (:class:`ReferencePlayer`; None: none), ``absolute`` as there.
        timeout: a point from the topic older than this (s wall) is stale.
        any_names: a point from the topic may name other joints (only its length is checked).

    Attributes:
        source: ``"bag"``, ``"builtin"`` or ``"topic"``.
    """

    def __init__(self, node, topic: str, joints: Sequence[str], bag: str = "",
                 trajectory: Callable | None = None, timeout: float = 0.5, absolute: bool = False,
                 any_names: bool = False):
        self.node, self.joints, self.any_names = node, list(joints), any_names
        self.source = "bag" if bag else "topic" if trajectory is None else "builtin"
        self.player = None
        if bag:
            self.player = ReferencePlayer.from_bag(node, bag, topic, joints)
        elif trajectory is not None:
            self.player = ReferencePlayer(node, topic, joints, trajectory, absolute=absolute)
        self.point = None
        node.inputs.add("reference", timeout=timeout, length=len(self.joints), required=self.player is None)
        if self.player is None:
            node.create_subscription(JointTrajectory, topic, self.on_message, stream_qos())

    def on_message(self, msg: JointTrajectory) -> None:
        """A point from the topic: kept when usable (else counted as rejected)."""
        ref = convert.reference_point(msg, None if self.any_names else self.joints)
        if self.node.accept("reference", None if ref is None else ref[0]):
            self.point = ref

    def __call__(self, t: float, q):
        """The reference ``(q, qd, qdd)`` ((n,) each) for the state of stamp ``t`` at ``q``: the
        played sample (published), else the topic's latest point; None when it is stale or none
        came yet."""
        if self.player is not None:
            return self.player(t, q)
        if self.point is None or not self.node.inputs.fresh("reference", time.monotonic()):
            return None
        return self.point
