"""``fit_simulation(covariance=False)`` (used by the k-fold fits of the leg identification, whose
spread over the folds is the uncertainty): the same optimum as with the covariance, no standard
errors, and 2p fewer simulations. Oracle: a closed-form exponential decay x(t) = x0 e^(-t / T)."""
from __future__ import annotations

import math

import numpy as np
import pytest

from cablelab.fit.simulation import fit_simulation
from cablelab.effects.base import Param

T_TRUE, X0 = 0.35, 2.0
t = np.linspace(0.0, 1.0, 200)
y = (X0 * np.exp(-t / T_TRUE) + 1e-3 * np.random.default_rng(0).standard_normal(t.size))[:, None]


def simulate(sets):
    return np.stack([X0 * np.exp(-t / s["T"])[:, None] for s in sets])


@pytest.mark.parametrize("cov", [True, False])
def test_optimum_with_and_without_covariance(cov):
    res = fit_simulation(simulate, [Param("T", "s", 0.6, 0.05, 2.0)], y, covariance=cov)
    assert res.params["T"] == pytest.approx(T_TRUE, rel=2e-3)
    assert math.isnan(res.stderr["T"]) != cov
    if cov:
        assert 0 < res.stderr["T"] < 1e-3


def test_without_covariance_saves_the_finite_difference_batch():
    p = [Param("T", "s", 0.6, 0.05, 2.0)]
    a = fit_simulation(simulate, p, y)
    b = fit_simulation(simulate, p, y, covariance=False)
    assert a.params["T"] == b.params["T"]
    assert a.evaluations - b.evaluations == 3   # 2p + 1 rollouts of the covariance batch, p = 1
