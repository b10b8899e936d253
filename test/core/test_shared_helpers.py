"""Helpers shared across plants, each against an independent oracle."""
from __future__ import annotations

import numpy as np
import pytest

from cablelab.effects.friction import coulomb_sign
from cablelab.errors import CablelabError
from cablelab.fit.simulation import free_run_windows, window_length, window_starts
from cablelab.dataset import Dataset
from cablelab.rotations import cross, matrix_to_quat, quat_to_matrix, wxyz_to_xyzw, xyzw_to_wxyz


def test_ros_quaternion_order_round_trip_and_meaning():
    # ROS (x, y, z, w) of +90 deg about z: (0, 0, sin 45, cos 45)
    ros = np.array([[0.0, 0.0, np.sqrt(0.5), np.sqrt(0.5)]])
    R = quat_to_matrix(xyzw_to_wxyz(ros))[0]
    np.testing.assert_allclose(R, [[0, -1, 0], [1, 0, 0], [0, 0, 1]], atol=1e-12)
    q = np.random.default_rng(0).normal(size=(20, 4))
    np.testing.assert_array_equal(xyzw_to_wxyz(wxyz_to_xyzw(q)), q)
    # matrix -> quaternion -> matrix with random unit quaternions
    q /= np.linalg.norm(q, axis=1, keepdims=True)
    np.testing.assert_allclose(quat_to_matrix(matrix_to_quat(quat_to_matrix(q))), quat_to_matrix(q),
                               atol=1e-12)


def test_cross_matches_numpy():
    a, b = np.random.default_rng(1).normal(size=(2, 7, 3))
    np.testing.assert_allclose(cross(a, b), np.cross(a, b), atol=1e-12)


def test_coulomb_sign_dead_band_is_strict():
    v = np.array([-2e-3, -1e-3, -5e-4, 0.0, 5e-4, 1e-3, 2e-3])
    assert coulomb_sign(v, 1e-3).tolist() == [-1, -1, 0, 0, 0, 1, 1]
    assert coulomb_sign(v).tolist() == np.sign(v).tolist()


def test_free_run_windows_and_window_starts():
    t = np.arange(103) * 0.01
    ds = Dataset(plant="axis", t=t, y=np.zeros(103), channels=("joint",), source="x")
    assert window_length(0.01, 0.25) == 25 and window_length(0.01, 0.001) == 2
    assert free_run_windows(ds, 0.25) == (25, 4)
    q = np.random.default_rng(2).normal(size=(103, 2))
    expect = np.array([q[25 * (i // 25)] for i in range(103)])     # per-sample oracle
    np.testing.assert_array_equal(window_starts(q, 25), expect)
    with pytest.raises(CablelabError, match="shorter than one free-run window"):
        free_run_windows(ds, 2.0)
