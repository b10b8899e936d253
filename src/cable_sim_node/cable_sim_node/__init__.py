"""cable_sim_node: a thin ROS 2 adapter over the cablelab core."""
