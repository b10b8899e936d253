"""The axis live estimator's core (ROS-free, what ``payload_estimator --plant axis`` runs per
sample): fed the MuJoCo axis driven by a multi-sine it recovers the true inertia, viscous
friction, Coulomb friction and effort offset (oracle: the simulator's truth), and ignores a
repeated or earlier stamp."""
from __future__ import annotations

import numpy as np
import pytest

from cablelab.description import load_description
from cablelab.plants.axis.estimator import AxisRlsEstimator
from cablelab.plants.axis.sim import DEFAULT_DESCRIPTION, AxisSim, AxisTruth

TRUTH = AxisTruth(inertia=2.0, viscous=5.0, coulomb=1.0, offset=0.3)


def _run(rate: float = 200.0, duration: float = 20.0):
    sim = AxisSim(load_description(DEFAULT_DESCRIPTION), TRUTH)
    est = AxisRlsEstimator(forgetting=1.0, stiction_velocity=1e-3)
    updates = 0
    for k in range(int(duration * rate)):
        t = k / rate
        u = 6.0 * np.sin(2 * np.pi * 0.3 * t) + 3.0 * np.sin(2 * np.pi * 1.1 * t + 1.0)
        t1, q, qd = sim.advance(u, 1.0 / rate)         # u held over the period ending at t1
        updates += est.step(t1, q, qd, sim.measured_effort(u))
    return est, updates


def test_recovers_the_simulated_axis():
    est, updates = _run()
    assert updates == 20 * 200 - 1                      # every sample after the first
    M, Fv, Fc, offset = est.theta
    assert M == pytest.approx(TRUTH.inertia, rel=0.05)
    assert Fv == pytest.approx(TRUTH.viscous, rel=0.05)
    assert Fc == pytest.approx(TRUTH.coulomb, rel=0.15)
    assert offset == pytest.approx(TRUTH.offset, abs=0.05)


def test_repeated_or_earlier_stamp_is_ignored():
    est = AxisRlsEstimator()
    assert not est.step(1.0, 0.0, 0.0, 0.0)               # the first sample only starts the pair
    assert est.step(1.01, 0.001, 0.1, 1.0)
    before = est.theta.copy()
    assert not est.step(1.01, 0.002, 0.1, 1.0) and not est.step(1.0, 0.0, 0.0, 0.0)
    np.testing.assert_array_equal(est.theta, before)
