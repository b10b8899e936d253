"""The ``mjcf`` plant's topic names (CONTRACT section 2, "Any machine from its MuJoCo model"),
defined once. A description may remap each one (``mjcf.topics``: a real robot's own names)."""
from __future__ import annotations

JOINT_STATE = "sensor_msgs/msg/JointState"

#: key in ``mjcf.topics`` -> (default topic, message type)
TOPICS = {
    "joint_states": ("/mjcf/joint_states", JOINT_STATE),
    "cable_tensions": ("/mjcf/cable_tensions", JOINT_STATE),
    "reference": ("/mjcf/reference", "trajectory_msgs/msg/JointTrajectory"),
    "effort_commands": ("/mjcf/effort_commands", "std_msgs/msg/Float64MultiArray"),
    "payload_estimate": ("/mjcf/payload_estimate", "geometry_msgs/msg/InertiaStamped"),
    "ground_truth_joint_states": ("/mjcf/ground_truth/joint_states", JOINT_STATE),
    "markers": ("/mjcf/markers", "visualization_msgs/msg/MarkerArray"),   # 3D view (addition)
}


def topic(section, key: str) -> str:
    """The topic of ``key`` for a parsed ``mjcf:`` section (its remapping, else the default)."""
    remap = getattr(section, "topics", None) or {}
    return remap.get(key, TOPICS[key][0])


def contract_topics(section=None) -> dict[str, str]:
    """topic -> type of every topic of a recording (with the section's remapping)."""
    return {topic(section, k): typ for k, (_, typ) in TOPICS.items()}
