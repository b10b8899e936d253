"""The mjcf controller's ROS-free helpers: the built-in sine as a played trajectory (oracle: its
derivatives by finite differences, and the first point at the held position) and the payload
estimates the law takes."""
import numpy as np
import pytest

from cablelab.plants.mjcf.control import MAX_PAYLOAD, MAX_REACH, payload_values, sine_trajectory


def test_sine_trajectory_starts_at_the_held_position_and_differentiates_consistently():
    q0 = np.array([0.3, -1.0, 2.0])
    play = sine_trajectory(3, 0.4, 0.7)
    tt = np.linspace(0.0, 3.0, 30001)
    q, qd, qdd = play(tt, q0)
    assert q.shape == qd.shape == qdd.shape == (len(tt), 3)
    np.testing.assert_allclose(q[0], q0, atol=1e-15)
    dt = tt[1] - tt[0]
    np.testing.assert_allclose(np.gradient(q, dt, axis=0)[1:-1], qd[1:-1], atol=1e-6)
    np.testing.assert_allclose(np.gradient(qd, dt, axis=0)[1:-1], qdd[1:-1], atol=1e-5)
    assert np.ptp(q, axis=0).min() > 0.5                    # every joint moves (2 x amplitude ~ 0.8)


@pytest.mark.parametrize("m, com, ok", [
    (1.2, [0.0, 0.1, -0.2], True), (0.0, [0, 0, 0], True), (-0.1, [0, 0, 0], False),
    (MAX_PAYLOAD * 1.01, [0, 0, 0], False), (1.0, [0, 0, MAX_REACH * 1.01], False),
    (float("nan"), [0, 0, 0], False), (1.0, [0, float("inf"), 0], False), (1.0, [0, 0], False)])
def test_payload_values_take_only_a_physical_payload(m, com, ok):
    v = payload_values(m, com)
    assert (v is not None) == ok
    if ok:
        np.testing.assert_array_equal(v, [m, *com])
