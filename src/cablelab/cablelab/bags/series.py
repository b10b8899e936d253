"""Contract message types and the numpy series a bag topic decodes into (one dataclass per
message shape, arrays over time, SI units)."""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from ..errors import CablelabError

# ---------------------------------------------------------------------------------------- types
JOINT_STATE = "sensor_msgs/msg/JointState"
POSE_STAMPED = "geometry_msgs/msg/PoseStamped"
INERTIA_STAMPED = "geometry_msgs/msg/InertiaStamped"
FLOAT64_MULTI_ARRAY = "std_msgs/msg/Float64MultiArray"
JOINT_TRAJECTORY = "trajectory_msgs/msg/JointTrajectory"
MULTIDOF_TRAJECTORY = "trajectory_msgs/msg/MultiDOFJointTrajectory"
STRING = "std_msgs/msg/String"
CLOCK = "rosgraph_msgs/msg/Clock"

DESCRIPTION_TOPIC = "/plant_description"
CLOCK_TOPIC = "/clock"


# ---------------------------------------------------------------------------------------- series
@dataclass
class JointStateSeries:
    """sensor_msgs/JointState over time. Arrays (N, k) in the column order of ``names``; NaN
    where a message left the field empty or did not contain that joint."""

    t: np.ndarray
    names: list[str]
    position: np.ndarray
    velocity: np.ndarray
    effort: np.ndarray
    t_receive: np.ndarray

    def column(self, name: str) -> int:
        """Index of a joint in the arrays (CablelabError naming the joint if absent)."""
        try:
            return self.names.index(name)
        except ValueError:
            raise CablelabError(f"joint {name!r} not in {self.names}") from None


@dataclass
class PoseSeries:
    """geometry_msgs/PoseStamped over time: position (N, 3) m, quaternion (N, 4) as x, y, z, w."""

    t: np.ndarray
    position: np.ndarray
    quaternion: np.ndarray
    frame_id: str = ""
    t_receive: np.ndarray | None = None


@dataclass
class InertiaSeries:
    """geometry_msgs/InertiaStamped over time: mass m (N,) kg, centre of mass com (N, 3) m."""

    t: np.ndarray
    m: np.ndarray
    com: np.ndarray
    frame_id: str = ""
    t_receive: np.ndarray | None = None


@dataclass
class ArraySeries:
    """std_msgs/Float64MultiArray over time. ``t`` is the log time (the message has no header);
    ``data`` (N, k), NaN-padded if lengths differ."""

    t: np.ndarray
    data: np.ndarray
    t_receive: np.ndarray | None = None


@dataclass
class JointTrajectorySeries:
    """trajectory_msgs/JointTrajectory, first point of each message: (N, k), NaN if empty."""

    t: np.ndarray
    names: list[str]
    positions: np.ndarray
    velocities: np.ndarray
    accelerations: np.ndarray
    t_receive: np.ndarray | None = None


@dataclass
class MultiDofSeries:
    """trajectory_msgs/MultiDOFJointTrajectory, first point and first joint of each message.
    position (N, 3) m, quaternion (N, 4) x, y, z, w, velocities and accelerations (N, 3), NaN if
    empty."""

    t: np.ndarray
    position: np.ndarray
    quaternion: np.ndarray
    linear_velocity: np.ndarray
    angular_velocity: np.ndarray
    linear_acceleration: np.ndarray
    angular_acceleration: np.ndarray
    t_receive: np.ndarray | None = None


# ---------------------------------------------------------------------------------------- reading
