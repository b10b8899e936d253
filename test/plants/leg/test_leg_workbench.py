"""Workbench on leg bags (spec 003_leg.md sec. 7; the demo's case; B7's diagnose part on the
round-trip records is in test_leg_identify.py): data from the MuJoCo plant
with the impact map and a 2.7 N spring preload hidden; ``diagnose --greedy`` on the 003 model
without impact must add ``impact_restitution`` then ``spring_preload`` and the error must fall.
The workbench fit is the linear inverse model of plants/leg/dataset.py, which shares no code with
the hybrid simulator that made the data."""
from __future__ import annotations

import math
from pathlib import Path

import pytest

import cablelab.plants.leg as leg_pkg
from cablelab.description import load_description
from cablelab.plants.leg.description import leg_of
from cablelab.plants.leg.hybrid import LegParams
from cablelab.plants.leg.sim import simulate, write_bag
from cablelab.workbench import build_model, diagnose, load

DESC = Path(leg_pkg.__file__).parent / "data" / "leg.yaml"
TRUE = LegParams(F0=2.7)
SCHEDULE = [(1.5, 0.30), (2.5, 0.35), (3.0, 0.30), (2.0, 0.35), (2.5, 0.30)]  # (T N m, P s), 4 s each


def _law(t, sim):
    T, P = SCHEDULE[min(int(t // 4.0), len(SCHEDULE) - 1)]
    return T * math.sin(2 * math.pi * (t - sim.t_d) / P)


@pytest.fixture(scope="module")
def traj():
    return simulate(TRUE, TRUE.z_td + 0.03, 0.0, 20.0, _law)


@pytest.fixture(scope="module")
def bag(traj, tmp_path_factory):
    path = tmp_path_factory.mktemp("leg") / "hidden"
    write_bag(path, traj, DESC.read_text())
    return path


def test_greedy_adds_impact_then_preload(bag):
    plant, desc, ds = load(bag)
    assert plant.name == "leg" and ds.n > 19000
    # the leg's mass is weighed (the description's 1.55 kg): with m free, F_0 and a stance inertia
    # m - F_0 / g (phase_effective_mass) are one stance force (test_leg_phase_mass.py)
    out = diagnose(ds, build_model(plant, desc, fixed={"m": leg_of(desc).mass}), plant.candidates(desc),
                   greedy_mode=True).to_json()
    steps = out["greedy"]
    assert [s["added"] for s in steps[1:3]] == ["impact_restitution", "spring_preload"]
    errs = [s["error"] for s in steps]
    assert errs[1] < 0.5 * errs[0] and errs[2] < errs[1]
    assert out["ranking"][0]["effect"] == "impact_restitution" and out["ranking"][0]["significant"]
    p = steps[2]["params"]
    beta_td, beta_lo = 1 - p["c_td"] / p["m"], 1 - p["c_lo"] / p["m"]
    assert beta_td == pytest.approx(TRUE.beta_td, rel=0.05)
    assert beta_lo == pytest.approx(TRUE.beta_lo, rel=0.05)
    assert p["F0"] == pytest.approx(2.7, rel=0.10)


def test_bag_without_contact_falls_back_to_height_and_says_so(traj, tmp_path):
    from cablelab.workbench import load_checked

    path = tmp_path / "nocontact"
    write_bag(path, traj, DESC.read_text(), contact=False)
    _, _, ds, check = load_checked(path)            # the warning of the text and JSON output
    assert any("no /leg/contact" in w and "height" in w for w in check.warnings), check.warnings
    agree = (ds.signals["contact"] == traj.phase).mean()
    assert agree > 0.98


def test_description_without_link_length_fails_in_one_line(tmp_path):
    bad = DESC.read_text().replace("  link_length: 0.15", "")
    from cablelab.errors import CablelabError

    with pytest.raises(CablelabError, match=r"leg\.link_length: missing required key"):
        load_description(bad)


def test_a_start_state_resent_until_answered_is_one_sample(tmp_path):
    """A lock-stepped simulator resends its start state until the controller answers it: the bag
    then holds that sample several times. The dataset is the one of the bag without the repeats
    (oracle: the same run written once per sample)."""
    import dataclasses

    import numpy as np

    from cablelab.plants.leg.excite import closed_loop

    run = closed_loop(TRUE, TRUE.z_td + 0.012, 3.0, z0=TRUE.z_td + 0.03, seed=None)
    rep = np.r_[0, 0, 0, np.arange(len(run.t))]                 # the start state three more times
    resent = dataclasses.replace(run, **{f.name: getattr(run, f.name)[rep] for f in dataclasses.fields(run)
                                         if isinstance(getattr(run, f.name), np.ndarray)})
    write_bag(tmp_path / "once", run, DESC.read_text())
    write_bag(tmp_path / "resent", resent, DESC.read_text())
    _, _, a = load(tmp_path / "once")
    _, _, b = load(tmp_path / "resent")
    assert b.n == a.n == len(run.t)
    np.testing.assert_array_equal(b.t, a.t)
    np.testing.assert_array_equal(b.valid, a.valid)
    np.testing.assert_allclose(b.y[a.valid], a.y[a.valid], rtol=0, atol=1e-12)
    for k in ("acc", "stance", "impulse_td"):
        np.testing.assert_allclose(b.signals[k][a.valid], a.signals[k][a.valid], rtol=0, atol=1e-12)
