"""The leg simulator node's plant (:class:`cablelab.plants.leg.live.LiveLeg`, ROS-free): the
encoder reading is the true height quantised to the description's resolution (within half a
step, on the grid), its velocity the backward difference of the readings, the motor angle that
of the two-link leg (z = 2 L cos theta, 0 when straight); the torque acts in stance only; the true mass and
preload are the node parameters' (oracle: the description's values scaled)."""
from __future__ import annotations

import numpy as np
import pytest

from cablelab.plants.leg.description import leg_of, load_leg_description
from cablelab.plants.leg.hybrid import STANCE
from cablelab.plants.leg.live import LiveLeg


def test_readings_follow_the_measurement_model():
    desc = load_leg_description()
    res = leg_of(desc).encoder_resolution
    live = LiveLeg(desc, rate=1000.0)
    readings, truth = [], []
    for _ in range(600):
        readings.append(live.step(0.5))
        truth.append(live.sim.z)
    z, zd, theta = np.array(readings).T
    assert np.all(np.abs(z - np.array(truth)) <= res / 2 + 1e-12)
    np.testing.assert_allclose(z / res, np.round(z / res), atol=1e-6)
    np.testing.assert_allclose(zd[1:], np.diff(z) * 1000.0, rtol=1e-12)
    assert zd[0] == 0.0
    folded = z <= 2 * live.sim.p.L                      # above: the leg is straight, theta 0
    assert folded.any() and (~folded).any()
    np.testing.assert_allclose(2 * live.sim.p.L * np.cos(theta[folded]), z[folded], atol=1e-12)
    assert np.all(theta[~folded] == 0.0)


def test_torque_acts_in_stance_only_and_truth_is_the_parameters():
    desc = load_leg_description()
    nominal = leg_of(desc).params(desc.gravity)
    a, b = (LiveLeg(desc, mass_scale=1.2, preload=3.0, z0_offset=0.03) for _ in range(2))
    assert a.sim.p.m == pytest.approx(1.2 * nominal.m) and a.sim.p.F0 == 3.0
    assert a.sim.z == pytest.approx(nominal.z_td + 0.03)
    assert a.sim.phase != STANCE                       # starts in flight above z_td
    while a.sim.phase != STANCE:                        # different torques in flight: same motion
        assert a.step(2.0) == b.step(-2.0)
    a.step(2.0), b.step(-2.0)
    assert a.sim.z != b.sim.z                           # in stance the torque acts
    assert LiveLeg(desc).sim.p.F0 == nominal.F0           # NaN preload: the description's
