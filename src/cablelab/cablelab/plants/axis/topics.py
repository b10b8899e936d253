"""The axis plant's topic names (CONTRACT.md section 2 and the additions in docs/nodes.md), defined
once: the nodes, the registration and the fleet bag writer import them from here."""
from __future__ import annotations

JOINT_STATE = "sensor_msgs/msg/JointState"

JOINT_STATES = "/axis/joint_states"            # joint: position, velocity, effort = measured force
REFERENCE = "/axis/reference"                  # joint reference: position, velocity, acceleration
EFFORT_COMMAND = "/axis/effort_command"        # drive command (addition)
PARAMETER_ESTIMATE = "/axis/parameter_estimate"    # live [M, Fv, Fc, offset] (addition)
GROUND_TRUTH = "/axis/ground_truth/joint_states"   # effort = true applied force (addition)
MARKERS = "/axis/markers"                      # the machine in 3D for Foxglove (addition)

#: topic -> message type of every axis topic a recording holds
TYPES = {
    JOINT_STATES: JOINT_STATE,
    REFERENCE: "trajectory_msgs/msg/JointTrajectory",
    EFFORT_COMMAND: "std_msgs/msg/Float64MultiArray",
    PARAMETER_ESTIMATE: "std_msgs/msg/Float64MultiArray",
    GROUND_TRUTH: JOINT_STATE,
    MARKERS: "visualization_msgs/msg/MarkerArray",
}
