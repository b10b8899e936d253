"""The mjcf plant's ROS 2 nodes, one module per role (``sim``), each with ``make_node()``; run
by the node executables (``cable_sim_node --plant mjcf -p description:=FILE``)."""
