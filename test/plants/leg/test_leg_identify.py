"""Acceptance tests B6 (identification round trip) and B7 (the impact map matters) of spec
003_leg.md sec. 8, on data the fitting code did not generate: 20 records of the independent scipy
reference (continuous eq. 26 torque, T 0.5-3 N m, P 0.25-0.40 s) sampled at 1 kHz with the
0.09 mm encoder and differentiated velocity, about 60 apex-to-apex strides. B7's diagnose part
runs the workbench on the same records."""
from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

import cablelab.plants.leg as leg_pkg
from cablelab.description import load_description
from cablelab.diagnose.ranking import rank_candidates
from cablelab.fit import identify as identify_linear
from cablelab.model import Model
from cablelab.plants.leg import effects
from cablelab.plants.leg.dataset import dataset_from_records
from cablelab.plants.leg.hybrid import LegParams
from cablelab.plants.leg.identify import identify, record_from_trajectory, stride_segments
from cablelab.plants.leg.reference import sampled_trajectory

TRUE = LegParams()


@pytest.fixture(scope="module")
def records():
    rng = np.random.default_rng(1)
    recs = []
    for i in range(20):
        T, P = rng.uniform(0.5, 3.0), rng.uniform(0.25, 0.40)
        tr = sampled_trajectory(TRUE, TRUE.z_td + rng.uniform(0.01, 0.04), 0.0, 1.8, T, P, seed=i)
        recs.append(record_from_trajectory(tr))
    assert 55 <= len(stride_segments(recs)) <= 70
    return recs


@pytest.fixture(scope="module")
def result(records):
    return identify(records, folds=(5, 10, 10))


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


def test_b7_diagnose_on_the_same_records_ranks_impact_first(records):
    """B7, diagnose part: the workbench (linear inverse model, plants/leg/dataset.py) on the same
    20 reference records as the round trip, each filtered on its own, on 003's model without the
    impact map: ``impact_restitution`` is first and significant, its betas within 5 %, and the
    held-out error falls below 5 % once it is added."""
    desc = load_description((Path(leg_pkg.__file__).parent / "data" / "leg.yaml").read_text())
    ds = dataset_from_records([(r.t, r.z, r.contact, r.tau) for r in records], desc)
    d = rank_candidates(Model("leg", effects.BASELINE), ds, effects.CANDIDATES)
    top = d.ranking[0]
    assert top.effect == "impact_restitution" and top.significant, [r.effect for r in d.ranking]
    assert d.baseline_error > 0.10 and top.error_after < 0.05          # held-out NRMSE of the force
    p = identify_linear(Model("leg", effects.BASELINE + ("impact_restitution",)), ds).params
    assert 1 - p["c_td"] / p["m"] == pytest.approx(TRUE.beta_td, rel=0.05)
    assert 1 - p["c_lo"] / p["m"] == pytest.approx(TRUE.beta_lo, rel=0.05)
    assert p["m"] == pytest.approx(TRUE.m, rel=0.02)
