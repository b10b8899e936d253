"""The contract topics of each plant (CONTRACT section 2) with their message types.

ROS-free: used by the recorder to pick a plant's topic set and by tools that check bags.
Additions beyond the contract tables are marked (documented in docs/nodes.md).
"""
from __future__ import annotations

COMMON = {
    "/clock": "rosgraph_msgs/msg/Clock",
    "/plant_description": "std_msgs/msg/String",
}

PLANT_TOPICS: dict[str, dict[str, str]] = {
    "cdpr": {
        "/cdpr/joint_states": "sensor_msgs/msg/JointState",
        "/cdpr/cable_tensions": "sensor_msgs/msg/JointState",
        "/cdpr/platform_pose": "geometry_msgs/msg/PoseStamped",
        "/cdpr/reference": "trajectory_msgs/msg/MultiDOFJointTrajectory",
        "/cdpr/effort_commands": "std_msgs/msg/Float64MultiArray",
        "/cdpr/payload_estimate": "geometry_msgs/msg/InertiaStamped",
        "/cdpr/ground_truth/pose": "geometry_msgs/msg/PoseStamped",
        "/cdpr/ground_truth/payload": "geometry_msgs/msg/InertiaStamped",
    },
    "crane": {
        "/crane/joint_states": "sensor_msgs/msg/JointState",
        "/crane/boom_tip_pose": "geometry_msgs/msg/PoseStamped",
        "/crane/payload_pose": "geometry_msgs/msg/PoseStamped",
        "/crane/reference": "trajectory_msgs/msg/JointTrajectory",
        "/crane/effort_commands": "std_msgs/msg/Float64MultiArray",
        "/crane/swing_estimate": "sensor_msgs/msg/JointState",
        "/crane/ground_truth/swing": "sensor_msgs/msg/JointState",
    },
    "axis": {
        "/axis/joint_states": "sensor_msgs/msg/JointState",
        "/axis/reference": "trajectory_msgs/msg/JointTrajectory",
        # additions (docs/nodes.md): command input, live parameter estimate, simulation truth
        "/axis/effort_command": "std_msgs/msg/Float64MultiArray",
        "/axis/parameter_estimate": "std_msgs/msg/Float64MultiArray",
        "/axis/ground_truth/joint_states": "sensor_msgs/msg/JointState",
    },
    # issue 11 (spec 000_suspended.md sec. 5); temporary wiring until the plant folder owns it
    "suspended": {
        "/suspended/joint_states": "sensor_msgs/msg/JointState",
        "/suspended/platform_pose": "geometry_msgs/msg/PoseStamped",
        "/suspended/imu": "sensor_msgs/msg/Imu",
        "/suspended/reference": "trajectory_msgs/msg/JointTrajectory",
        "/suspended/effort_commands": "std_msgs/msg/Float64MultiArray",
        "/suspended/swing_estimate": "sensor_msgs/msg/JointState",
        "/suspended/ground_truth/swing": "sensor_msgs/msg/JointState",
        "/suspended/ground_truth/virtual_joints": "sensor_msgs/msg/JointState",
    },
}


def plant_topics(plant: str) -> dict[str, str]:
    """All topics (name -> type) a recording of ``plant`` should hold, /clock and
    /plant_description included.

    Raises:
        CablelabError: unknown plant.
    """
    from .errors import CablelabError

    if plant not in PLANT_TOPICS:
        raise CablelabError(f"unknown plant {plant!r} (topic sets exist for: "
                            f"{', '.join(sorted(PLANT_TOPICS))})")
    return {**COMMON, **PLANT_TOPICS[plant]}
