"""The leg's topic names (CONTRACT.md section 2, spec 003_leg.md sec. 5), defined once: the nodes,
the registration, the dataset and the offline bag writer import them from here."""
from __future__ import annotations

JOINT_STATE = "sensor_msgs/msg/JointState"

JOINT_STATES = "/leg/joint_states"          # body (height, velocity, F_in), motor (angle, torque)
CONTACT = "/leg/contact"                    # contact switch: 1.0 stance, 0.0 flight
REFERENCE = "/leg/reference"                # desired apex height
EFFORT_COMMANDS = "/leg/effort_commands"    # motor torque
HOP_ESTIMATE = "/leg/hop_estimate"          # height, phase, apex_height, grf
GROUND_TRUTH = "/leg/ground_truth/state"    # simulation truth, the names of HOP_ESTIMATE
MARKERS = "/leg/markers"                       # the machine in 3D for Foxglove (addition)

#: topic -> message type of every leg topic a recording holds
TYPES = {
    JOINT_STATES: JOINT_STATE,
    CONTACT: JOINT_STATE,
    REFERENCE: "trajectory_msgs/msg/JointTrajectory",
    EFFORT_COMMANDS: "std_msgs/msg/Float64MultiArray",
    HOP_ESTIMATE: JOINT_STATE,
    GROUND_TRUTH: JOINT_STATE,
    MARKERS: "visualization_msgs/msg/MarkerArray",
}
