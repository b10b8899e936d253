"""rosbag2 MCAP bags: read contract topics into numpy arrays, write them from numpy arrays.

A bag is a rosbag2 directory (``metadata.yaml`` + ``<name>.mcap``, ROS 2 Jazzy typestore, CDR
messages with ``ros2msg`` schemas) as written by ``ros2 bag record -s mcap``; it opens in
``ros2 bag info``, Foxglove and the mcap tools. A bare ``.mcap`` file is accepted too.

Reading: :func:`open_bag` reads every message of the bag in one pass (rosbags' MCAP reader) and
decodes each topic on demand with the vectorised CDR codec of :mod:`cablelab.cdr` into small
dataclasses of numpy arrays (:class:`JointStateSeries`, :class:`PoseSeries`, ...). Times are in
seconds: ``t`` is the header stamp (sim time when /clock is published), ``t_receive`` the bag's
log time.

Writing: :class:`BagWriter` writes whole time series per call (``write_joint_states(topic, t,
names, position, ...)``), vectorised the same way, plus ``write_raw`` for already-serialised
messages (the recorder).

Every problem with the user's input raises :class:`~cablelab.errors.CablelabError` with one line
naming the path, topic or types.
"""
from .reader import Bag, bag_info, open_bag
from .series import (CLOCK, CLOCK_TOPIC, DESCRIPTION_TOPIC, INERTIA_STAMPED, FLOAT64_MULTI_ARRAY, JOINT_STATE,
                     JOINT_TRAJECTORY, MULTIDOF_TRAJECTORY, POSE_STAMPED, STRING, ArraySeries,
                     InertiaSeries, JointStateSeries, JointTrajectorySeries, MultiDofSeries,
                     PoseSeries)
from .writer import BagWriter, qos_profile

__all__ = ["ArraySeries", "Bag", "BagWriter", "CLOCK", "CLOCK_TOPIC", "DESCRIPTION_TOPIC", "FLOAT64_MULTI_ARRAY",
           "INERTIA_STAMPED", "JOINT_STATE", "JOINT_TRAJECTORY", "JointStateSeries",
           "JointTrajectorySeries", "MULTIDOF_TRAJECTORY", "MultiDofSeries", "POSE_STAMPED",
           "PoseSeries", "STRING", "InertiaSeries", "bag_info", "open_bag", "qos_profile"]
