"""The CDPR's topic names (CONTRACT.md section 2), defined once: the nodes, the registration, the
offline bag writer, the markers and the demo import them from here."""
from __future__ import annotations

JOINT_STATE = "sensor_msgs/msg/JointState"
POSE_STAMPED = "geometry_msgs/msg/PoseStamped"
INERTIA_STAMPED = "geometry_msgs/msg/InertiaStamped"

JOINT_STATES = "/cdpr/joint_states"            # winch_i: angle, rate, motor torque
CABLE_TENSIONS = "/cdpr/cable_tensions"        # cable_i: effort = measured tension
PLATFORM_POSE = "/cdpr/platform_pose"          # measured platform pose
REFERENCE = "/cdpr/reference"                  # desired platform trajectory
EFFORT_COMMANDS = "/cdpr/effort_commands"      # winch torques
PAYLOAD_ESTIMATE = "/cdpr/payload_estimate"    # live payload mass and centre of mass
GROUND_TRUTH_POSE = "/cdpr/ground_truth/pose"
GROUND_TRUTH_PAYLOAD = "/cdpr/ground_truth/payload"
MARKERS = "/cdpr/markers"                      # 3D view of the simulator (visualization_msgs)

#: topic -> message type of every CDPR topic a recording holds
TYPES = {
    JOINT_STATES: JOINT_STATE,
    CABLE_TENSIONS: JOINT_STATE,
    PLATFORM_POSE: POSE_STAMPED,
    REFERENCE: "trajectory_msgs/msg/MultiDOFJointTrajectory",
    EFFORT_COMMANDS: "std_msgs/msg/Float64MultiArray",
    PAYLOAD_ESTIMATE: INERTIA_STAMPED,
    GROUND_TRUTH_POSE: POSE_STAMPED,
    GROUND_TRUTH_PAYLOAD: INERTIA_STAMPED,
    MARKERS: "visualization_msgs/msg/MarkerArray",
}
