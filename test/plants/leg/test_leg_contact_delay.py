"""Effect ``contact_delay`` (spec 003_leg.md sec. 7): the contact switch closes and opens tau_c
after the true touch-down and lift-off. Data from the independent scipy reference
(plants/leg/reference.py, ``solve_ivp`` with events; 0.09 mm encoder, 1 kHz) with the switch 8 ms
late: on the 003 model (impact map included) ``diagnose`` ranks ``contact_delay`` first and
significant with tau_c within 1 ms; on the same experiment with a punctual switch (the control)
it is not significant. The workbench fit is the linear inverse model of plants/leg/dataset.py,
which shares no code with the reference."""
from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

import cablelab.plants.leg as leg_pkg
from cablelab.description import load_description
from cablelab.diagnose.ranking import fold_indices, rank_candidates
from cablelab.model import Model
from cablelab.plants.leg import effects
from cablelab.plants.leg.dataset import advance_contact, dataset_from_arrays
from cablelab.plants.leg.hybrid import LegParams
from cablelab.plants.leg.reference import sampled_trajectory

DESC = load_description((Path(leg_pkg.__file__).parent / "data" / "leg.yaml").read_text())
TRUE = LegParams()
SCHEDULE = [(1.5, 0.30), (2.5, 0.35), (3.0, 0.30), (2.0, 0.35), (2.5, 0.30)]  # (T N m, P s), 4 s each
DELAY = 0.008


def _data(delay: float):
    tr = sampled_trajectory(TRUE, TRUE.z_td + 0.03, 0.0, 20.0, schedule=SCHEDULE, block_s=4.0, seed=3,
                            contact_delay=delay)
    return tr, dataset_from_arrays(tr.t, tr.z_meas, tr.contact, tr.tau, DESC, source=f"reference {delay}")


@pytest.fixture(scope="module")
def delayed():
    return _data(DELAY)


@pytest.fixture(scope="module")
def punctual():
    return _data(0.0)


def _nominal():
    return Model("leg", effects.BASELINE + ("impact_restitution",))


def test_switch_really_is_late_in_the_data(delayed):
    tr, _ = delayed
    edges = np.flatnonzero(np.diff(tr.contact)) + 1
    truth = np.flatnonzero(np.diff(tr.phase)) + 1
    assert len(edges) == len(truth) > 60
    np.testing.assert_array_equal(edges - truth, 8)


def test_whole_sample_advance_equals_a_dataset_of_the_shifted_switch(delayed):
    """Second implementation: the dataset built from the switch array moved 8 samples earlier."""
    tr, ds = delayed
    moved = advance_contact(ds, DELAY)
    contact = np.r_[tr.contact[8:], np.full(8, tr.contact[-1])]
    direct = dataset_from_arrays(tr.t, tr.z_meas, contact, tr.tau, DESC)
    ok = ds.valid
    np.testing.assert_allclose(moved.y[ok], direct.y[ok], rtol=0, atol=1e-9)
    for k in ("impulse_td", "impulse_lo", "zd_stance", "stance", "contact", "f_in"):
        np.testing.assert_allclose(moved.signals[k][ok], direct.signals[k][ok], rtol=0, atol=1e-9,
                                   err_msg=k)
    assert (moved.regimes["phase"] == direct.regimes["phase"]).all()
    # and the advanced switch is the true phase
    assert np.mean(moved.signals["contact"][ok] == tr.phase[ok]) == 1.0


def test_transform_on_a_fold_is_the_fold_of_the_transform(delayed):
    """Cross-validation folds are subsets with a gap: the rebuilt signals of a fold's samples must
    be those of the full record (filters run on the whole record, not across the fold's gap)."""
    _, ds = delayed
    train, _ = fold_indices(ds.n, 5)[2]
    full = advance_contact(ds, 0.0057)
    fold = advance_contact(ds.subset(train), 0.0057)
    np.testing.assert_array_equal(fold.y, full.y[train])
    for k in ("impulse_td", "impulse_lo", "stance", "e2"):
        np.testing.assert_array_equal(fold.signals[k], full.signals[k][train])
    # a fractional advance is the blend of the two whole-sample ones (the switch is interpolated)
    a, b = advance_contact(ds, 0.005), advance_contact(ds, 0.006)
    np.testing.assert_allclose(full.y, 0.3 * a.y + 0.7 * b.y, atol=1e-9)


def test_diagnose_ranks_contact_delay_first_with_tau_c(delayed):
    _, ds = delayed
    d = rank_candidates(_nominal(), ds, effects.CANDIDATES)
    top = d.ranking[0]
    assert top.effect == "contact_delay" and top.significant, [r.effect for r in d.ranking]
    assert top.params["tau_c"] == pytest.approx(DELAY, abs=1e-3)
    assert top.error_after < 0.5 * top.error_before


def test_control_without_delay_does_not_call_it_significant(punctual):
    _, ds = punctual
    d = rank_candidates(_nominal(), ds, effects.CANDIDATES)
    row = next(r for r in d.ranking if r.effect == "contact_delay")
    assert not row.significant
    assert row.params["tau_c"] < 1e-3
    assert d.best_significant() is None


def test_bag_and_contract_json(delayed, tmp_path):
    """The same data as a contract bag (``/leg/contact`` topic) through the workbench: load,
    diagnose on the 003 model, contract JSON with tau_c in seconds."""
    from cablelab.plants.leg.sim import write_bag
    from cablelab.workbench import build_model, diagnose, load

    tr, _ = delayed
    path = tmp_path / "late_switch"
    write_bag(path, tr, (Path(leg_pkg.__file__).parent / "data" / "leg.yaml").read_text())
    plant, desc, ds = load(path)
    model = build_model(plant, desc, effects=("impact_restitution",))
    out = diagnose(ds, model, plant.candidates(desc)).to_json()
    top = out["ranking"][0]
    assert top["effect"] == "contact_delay" and top["significant"]
    assert top["params"]["tau_c"] == pytest.approx(DELAY, abs=1e-3)


def test_greedy_from_the_no_impact_baseline(delayed):
    """From 003's model without the impact map (the plant's default baseline) greedy adds the impact
    map, then contact_delay, and no proxy (README, 'Effect contact_delay')."""
    from cablelab.workbench import diagnose

    _, ds = delayed
    out = diagnose(ds, Model("leg", effects.BASELINE), effects.BASELINE + effects.CANDIDATES,
                   greedy_mode=True).to_json()
    assert [s["added"] for s in out["greedy"][1:]] == ["impact_restitution", "contact_delay"]
    assert out["final"]["params"]["tau_c"] == pytest.approx(DELAY, abs=1e-3)
    assert out["greedy"][-1]["error"] < 0.3 * out["greedy"][0]["error"]
