"""Acceptance tests B6 (identification round trip) and B7 (the impact map matters) of spec
003_leg.md sec. 8, on data the fitting code did not generate: 20 records of the independent scipy
reference (continuous eq. 26 torque, T 0.5-3 N m, P 0.25-0.40 s) sampled at 1 kHz with the
0.09 mm encoder and differentiated velocity, about 60 apex-to-apex strides."""
from __future__ import annotations

import numpy as np
import pytest

from cablelab.plants.leg.hybrid import LegParams
from cablelab.plants.leg.identify import identify, record_from_trajectory, stride_segments
from cablelab.plants.leg.reference import sampled_trajectory

TRUE = LegParams()


@pytest.fixture(scope="module")
def result():
    rng = np.random.default_rng(1)
    recs = []
    for i in range(20):
        T, P = rng.uniform(0.5, 3.0), rng.uniform(0.25, 0.40)
        tr = sampled_trajectory(TRUE, TRUE.z_td + rng.uniform(0.01, 0.04), 0.0, 1.8, T, P, seed=i)
        recs.append(record_from_trajectory(tr))
    assert 55 <= len(stride_segments(recs)) <= 70
    return identify(recs, folds=(5, 10, 10))


def test_b6_round_trip_parameters(result):
    p = result.params
    assert p.m == pytest.approx(TRUE.m, rel=0.01)
    assert p.d_s == pytest.approx(TRUE.d_s, rel=0.05)
    assert p.d_f == pytest.approx(TRUE.d_f, rel=0.30)
    assert p.beta_lo == pytest.approx(TRUE.beta_lo, rel=0.03)
    assert p.beta_td == pytest.approx(TRUE.beta_td, rel=0.03)


def test_b6_cross_validated_nmse_table1_order(result):
    st, fl = result.stance.metrics, result.flight.metrics
    assert np.mean(st["nmse_pos"]) < 0.02 and np.mean(st["nmse_vel"]) < 0.02
    assert np.mean(fl["nmse_vel"]) < 0.01
    assert np.mean(fl["mae_pos"]) < 2e-3
    table = result.table1()
    assert table.count("\n") == 5 and "Stance position" in table and "Flight velocity" in table
    assert "| m | Stance |" in result.table2()


def test_b6_whole_stride_nmse_below_5_percent(result):
    sm = result.stride_metrics
    assert np.mean(sm["nmse_pos"]) < 0.05 and np.mean(sm["nmse_vel"]) < 0.05


def test_b7_no_impact_apex_error_at_least_3x(result):
    full, none = result.apex["full"], result.apex["no_impact"]
    assert np.mean(none["height"]) >= 3.0 * np.mean(full["height"])
    assert np.mean(none["time"]) > np.mean(full["time"])
    # and the whole-stride NMSE of the no-impact model is far worse (003 Fig. 11 direction)
    assert np.mean(result.apex["nmse_no_impact"]["nmse_pos"]) > 3 * np.mean(result.apex["nmse_full"]["nmse_pos"])
