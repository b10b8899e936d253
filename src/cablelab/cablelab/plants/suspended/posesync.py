"""The platform attitude a joint state is answered with (ROS-free): the arm controller's gravity
term needs the attitude of the state's own instant, but DDS does not order the pose and joint-state
topics between them. :class:`PoseSync` keeps the latest attitude and, with ``sync``, holds a joint
state newer than it until the pose of its stamp arrives (while poses flow)."""
from __future__ import annotations

import numpy as np

from ...rotations import quat_to_matrix, xyzw_to_wxyz

__all__ = ["PoseSync"]


class PoseSync:
    """Joint states paired with the platform attitude.

    Args:
        sync: hold a joint state until the pose of its stamp arrived (else answer at once with
            the latest attitude).

    Attributes:
        R: (3, 3) the latest platform attitude (identity before the first pose).
        t: stamp of the latest pose, s (-inf before the first).
    """

    def __init__(self, sync: bool):
        self.sync = sync
        self.R = np.eye(3)
        self.t = -np.inf
        self.pending: tuple | None = None     # (t, q, qd) waiting for its pose

    def pose(self, t: float, quat_xyzw) -> tuple | None:
        """Take the pose of stamp ``t`` (orientation as x, y, z, w; normalised here); the held
        joint state ``(t, q, qd)`` it completes, else None."""
        q = np.asarray(quat_xyzw, dtype=float)
        self.R = quat_to_matrix(xyzw_to_wxyz(q / np.linalg.norm(q)))
        self.t = t
        if self.pending is not None and t >= self.pending[0] - 1e-9:
            ready, self.pending = self.pending, None
            return ready
        return None

    def state(self, t: float, q, qd, poses_flow: bool) -> tuple | None:
        """A joint state of stamp ``t``: ``(t, q, qd)`` when it is answered now (with :attr:`R`),
        None when it is held for its pose (``sync``, newer than the latest pose, ``poses_flow``).
        A held state is replaced by the next one."""
        self.pending = None
        if self.sync and self.t < t - 1e-9 and poses_flow:
            self.pending = (t, q, qd)
            return None
        return t, q, qd
