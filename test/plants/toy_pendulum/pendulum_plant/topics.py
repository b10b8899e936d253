"""The plant's topic names, defined once: the nodes, the registration, the dataset and the bag
writer import them from here."""
from __future__ import annotations

JOINT_STATE = "sensor_msgs/msg/JointState"

JOINT_STATES = "/pendulum/joint_states"            # the hinge: angle, rate, applied torque
EFFORT_COMMANDS = "/pendulum/effort_commands"      # torque command (the controller node)
PARAMETER_ESTIMATE = "/pendulum/parameter_estimate"    # live inertia estimate (the estimator node)

#: topic -> message type of every topic a recording holds
TYPES = {
    JOINT_STATES: JOINT_STATE,
    EFFORT_COMMANDS: "std_msgs/msg/Float64MultiArray",
    PARAMETER_ESTIMATE: "std_msgs/msg/Float64MultiArray",
}
