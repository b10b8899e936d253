"""The suspended platform's topic names (CONTRACT.md section 2, spec 000_suspended.md sec. 5),
defined once: the nodes, the registration, the dataset and the bag writer import them from here."""
from __future__ import annotations

JOINT_STATE = "sensor_msgs/msg/JointState"
POSE = "geometry_msgs/msg/PoseStamped"

JOINT_STATES = "/suspended/joint_states"      # arm joints: position, velocity, effort = torque
PLATFORM_POSE = "/suspended/platform_pose"    # measured lower-platform pose
IMU = "/suspended/imu"                        # optional platform IMU
REFERENCE = "/suspended/reference"            # arm joint references
EFFORT_COMMANDS = "/suspended/effort_commands"
SWING_ESTIMATE = "/suspended/swing_estimate"  # swing_x, swing_y, yaw, r_x, r_y
GROUND_TRUTH_SWING = "/suspended/ground_truth/swing"
GROUND_TRUTH_VIRTUAL = "/suspended/ground_truth/virtual_joints"
#: optional: measured pose of the suspension point S (crane hook / drone), a measured input of
#: ``suspension_motion`` (docs/contract-additions.md)
SUSPENSION_POSE = "/suspended/suspension_pose"
MARKERS = "/suspended/markers"                 # the machine in 3D for Foxglove (addition)

#: topic -> message type of every suspended topic a recording holds
TYPES = {
    JOINT_STATES: JOINT_STATE,
    PLATFORM_POSE: POSE,
    IMU: "sensor_msgs/msg/Imu",
    REFERENCE: "trajectory_msgs/msg/JointTrajectory",
    EFFORT_COMMANDS: "std_msgs/msg/Float64MultiArray",
    SWING_ESTIMATE: JOINT_STATE,
    GROUND_TRUTH_SWING: JOINT_STATE,
    GROUND_TRUTH_VIRTUAL: JOINT_STATE,
    SUSPENSION_POSE: POSE,
    MARKERS: "visualization_msgs/msg/MarkerArray",
}
