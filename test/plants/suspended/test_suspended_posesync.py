"""The arm controller's pairing of joint states with the platform attitude (ROS-free,
:class:`cablelab.plants.suspended.posesync.PoseSync`): the attitude is the pose's rotation
(oracle: scipy's quaternion to matrix, any quaternion scale); with ``sync`` a state newer than
the latest pose waits for the pose of its stamp while poses flow, a newer state replaces a held
one, and without ``sync`` or without poses every state is answered at once."""
from __future__ import annotations

import numpy as np
from scipy.spatial.transform import Rotation

from cablelab.plants.suspended.posesync import PoseSync


def test_attitude_is_the_pose_rotation():
    ps = PoseSync(False)
    np.testing.assert_array_equal(ps.R, np.eye(3))
    quat = Rotation.from_rotvec([0.1, -0.2, 0.3]).as_quat()          # x, y, z, w
    ps.pose(1.0, 3.0 * quat)                                           # not normalised
    np.testing.assert_allclose(ps.R, Rotation.from_quat(quat).as_matrix(), atol=1e-12)


def test_sync_holds_a_state_until_the_pose_of_its_stamp():
    ps = PoseSync(True)
    q, qd = np.zeros(8), np.ones(8)
    ps.pose(1.0, [0, 0, 0, 1.0])
    assert ps.state(1.0, q, qd, poses_flow=True) == (1.0, q, qd)        # its pose is here
    assert ps.state(1.01, q, qd, poses_flow=True) is None               # held
    assert ps.state(1.02, q + 1, qd, poses_flow=True) is None           # replaces the held one
    assert ps.pose(1.01, [0, 0, 0, 1.0]) is None                        # too early for 1.02
    ready = ps.pose(1.02, [0, 0, np.sin(0.05), np.cos(0.05)])
    assert ready[0] == 1.02 and np.all(ready[1] == q + 1)
    assert ps.pose(1.03, [0, 0, 0, 1.0]) is None                        # answered once
    assert ps.state(2.0, q, qd, poses_flow=False) == (2.0, q, qd)       # poses stopped: at once


def test_without_sync_every_state_is_answered_at_once():
    ps = PoseSync(False)
    assert ps.state(5.0, 1, 2, poses_flow=True) == (5.0, 1, 2)
