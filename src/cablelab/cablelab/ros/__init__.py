"""ROS 2 shell of cablelab: the shared node machinery (imported only by nodes and ROS verbs).

Nothing in the ROS-free core imports this package. Modules:

* :mod:`.qos`          QoS profiles of the contract topics (transient-local /plant_description)
* :mod:`.convert`      message <-> numpy for the contract types
* :mod:`.diagnostics`  /diagnostics publisher (OK/WARN/ERROR + key values)
* :mod:`.clock`        /clock publisher for simulators
* :mod:`.inputs`       input validation and stale-input tracking (ROS-free, testable)
* :mod:`.runner`       ``run_node`` / ``plant_main``: init, --plant, --ros-args, spin, shutdown
* :mod:`.recorder`     the bag recorder node (``cablelab record``)
* :mod:`.replayer`     the bag replayer node (``cablelab replay``)
* :mod:`.launch`       start nodes as subprocesses on one ROS_DOMAIN_ID, wait for topics, stop
"""
