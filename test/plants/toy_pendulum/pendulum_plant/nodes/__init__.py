"""The plant's ROS 2 nodes, one module per role (``sim``, ``estimator``, ``controller``), each
with ``PARAMETERS`` (its ROS parameter specs) and ``make_node()``; run by the node executables
(``cable_sim_node --plant pendulum``, ``payload_estimator --plant pendulum``, ``pd_feedforward --plant
pendulum``). Nodes are adapters: messages to arrays, one call into the plant's ROS-free modules,
arrays to messages."""
