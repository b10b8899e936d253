"""pd_feedforward: a thin ROS 2 adapter over the cablelab core."""
