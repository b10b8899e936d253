"""Rotation helpers shared by every plant: quaternions, rotation matrices, cross products.

Conventions: cablelab and MuJoCo order unit quaternions (w, x, y, z); ROS messages (and the
bags) store them (x, y, z, w): convert at that boundary with :func:`xyzw_to_wxyz` /
:func:`wxyz_to_xyzw`. Rotation matrices map the body frame to the world frame. All functions are
vectorised over leading axes.
"""
from __future__ import annotations

import numpy as np

__all__ = ["cross", "quat_to_matrix", "matrix_to_quat", "wxyz_to_xyzw", "xyzw_to_wxyz"]


def wxyz_to_xyzw(q) -> np.ndarray:
    """Quaternions (..., 4) reordered from (w, x, y, z) (MuJoCo, cablelab) to (x, y, z, w) (ROS)."""
    return np.asarray(q, dtype=float)[..., [1, 2, 3, 0]]


def xyzw_to_wxyz(q) -> np.ndarray:
    """Quaternions (..., 4) reordered from (x, y, z, w) (ROS) to (w, x, y, z) (MuJoCo, cablelab)."""
    return np.asarray(q, dtype=float)[..., [3, 0, 1, 2]]


def cross(a: np.ndarray, b: np.ndarray) -> np.ndarray:
    """Cross product over the last axis (broadcasting), without np.cross's per-call overhead."""
    a0, a1, a2 = a[..., 0], a[..., 1], a[..., 2]
    b0, b1, b2 = b[..., 0], b[..., 1], b[..., 2]
    out = np.empty(np.broadcast_shapes(a.shape, b.shape))
    out[..., 0] = a1 * b2 - a2 * b1
    out[..., 1] = a2 * b0 - a0 * b2
    out[..., 2] = a0 * b1 - a1 * b0
    return out


def quat_to_matrix(q: np.ndarray) -> np.ndarray:
    """Rotation matrices (..., 3, 3) from unit quaternions (..., 4) ordered (w, x, y, z)."""
    q = np.asarray(q, dtype=float)
    q = q / np.linalg.norm(q, axis=-1, keepdims=True)
    w, x, y, z = np.moveaxis(q, -1, 0)
    return np.stack([
        np.stack([1 - 2 * (y * y + z * z), 2 * (x * y - w * z), 2 * (x * z + w * y)], -1),
        np.stack([2 * (x * y + w * z), 1 - 2 * (x * x + z * z), 2 * (y * z - w * x)], -1),
        np.stack([2 * (x * z - w * y), 2 * (y * z + w * x), 1 - 2 * (x * x + y * y)], -1),
    ], -2)


def matrix_to_quat(R: np.ndarray) -> np.ndarray:
    """Unit quaternions (..., 4) (w, x, y, z) from rotation matrices (..., 3, 3) (w >= 0)."""
    R = np.asarray(R, dtype=float)
    tr = R[..., 0, 0] + R[..., 1, 1] + R[..., 2, 2]
    w = 0.5 * np.sqrt(np.maximum(1.0 + tr, 0.0))
    x = 0.5 * np.sqrt(np.maximum(1.0 + R[..., 0, 0] - R[..., 1, 1] - R[..., 2, 2], 0.0))
    y = 0.5 * np.sqrt(np.maximum(1.0 - R[..., 0, 0] + R[..., 1, 1] - R[..., 2, 2], 0.0))
    z = 0.5 * np.sqrt(np.maximum(1.0 - R[..., 0, 0] - R[..., 1, 1] + R[..., 2, 2], 0.0))
    x = np.copysign(x, R[..., 2, 1] - R[..., 1, 2])
    y = np.copysign(y, R[..., 0, 2] - R[..., 2, 0])
    z = np.copysign(z, R[..., 1, 0] - R[..., 0, 1])
    q = np.stack([w, x, y, z], -1)
    return q / np.linalg.norm(q, axis=-1, keepdims=True)
