"""The crane's topic names (CONTRACT.md section 2), defined once: the nodes, the registration, the
offline bag writer, the markers and the demo import them from here."""
from __future__ import annotations

JOINT_STATE = "sensor_msgs/msg/JointState"
POSE = "geometry_msgs/msg/PoseStamped"

JOINT_STATES = "/crane/joint_states"           # slew, luff, hoist: position, velocity, effort
TIP_POSE = "/crane/boom_tip_pose"
PAYLOAD_POSE = "/crane/payload_pose"
SWING_ESTIMATE = "/crane/swing_estimate"       # theta1, theta2, rope_length
SWING_TRUTH = "/crane/ground_truth/swing"      # simulation truth, the names of SWING_ESTIMATE
REFERENCE = "/crane/reference"                 # joint references
EFFORT_COMMANDS = "/crane/effort_commands"     # slew, luff torque, hoist force
MARKERS = "/crane/markers"                     # 3D view of the simulator (visualization_msgs)

#: topic -> message type of every crane topic a recording holds
TYPES = {
    JOINT_STATES: JOINT_STATE,
    TIP_POSE: POSE,
    PAYLOAD_POSE: POSE,
    REFERENCE: "trajectory_msgs/msg/JointTrajectory",
    EFFORT_COMMANDS: "std_msgs/msg/Float64MultiArray",
    SWING_ESTIMATE: JOINT_STATE,
    SWING_TRUTH: JOINT_STATE,
    MARKERS: "visualization_msgs/msg/MarkerArray",
}
