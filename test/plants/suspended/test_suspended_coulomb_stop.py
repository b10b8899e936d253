"""A swing that dry friction in the suspension stops dead (the signature of Coulomb friction).

The record comes from bench/cases_suspended.py: the LiCAS four-tendon truth plant stepped by
MuJoCo with the friction applied as a force on the platform (not the virtual-joint chain the
workbench fits). Once the swing has stopped, the platform holds still at a finite angle: there
the friction is whatever balances gravity, not f_s sign(qd), and no candidate predicts those
samples; the dataset leaves them out (``dataset.rest_mask``).

Oracle for the friction value: the truth applies f_s / L on the platform, a torque f_s about S;
the workbench's swing equation is written with the description's nominal modal inertia J
(:func:`modal_inertias`) where the truth has M L^2 (M the truth platform's subtree mass, the
platform translating), so the fitted coefficient is f_s J / (M L^2)."""
import os
import sys

import numpy as np
import pytest

from cablelab import workbench
from cablelab.plants.suspended.dataset import modal_inertias, rest_mask
from cablelab.plants.suspended.mjcf import build_truth
from cablelab.plants.suspended.params import parameter_set

sys.path.insert(0, os.path.join(os.path.dirname(__file__), "..", "..", "..", "bench"))
import cases_suspended  # noqa: E402


def _diagnose(case, path):
    rec = cases_suspended.write_bag(case, path)
    plant, desc, ds = workbench.load(path)
    out = workbench.diagnose(ds, workbench.build_model(plant, desc), plant.candidates(desc)).to_json()
    return rec, ds, out


def test_swing_stopped_by_dry_friction_ranks_coulomb_first_with_its_value(tmp_path):
    case = cases_suspended.stopping_case(3, fs=0.3)
    rec, ds, out = _diagnose(case, tmp_path / "bag")
    # the premise: the swing stops dead within 20 s of the 60 s record
    moving = np.linalg.norm(rec["pos_true"][:, :2] - rec["pos_true"][-1, :2], axis=1) > 1e-3
    assert rec["t"][np.flatnonzero(moving)[-1]] < 20.0
    assert ds.signals["rest_share"] > 0.5
    first = out["ranking"][0]
    assert first["effect"] == "cable_joint_coulomb_friction" and first["significant"]
    assert first["error_after"] < 0.5 * first["error_before"]
    p = parameter_set("licas")
    m = build_truth(p)
    M = float(m.body_subtreemass[m.body("platform").id])
    expected = case.truth["fs"] * modal_inertias(p)[:2] / (M * p.L ** 2)
    got = np.array([first["params"]["fs8"], first["params"]["fs9"]])
    assert np.all(np.abs(got / expected - 1.0) < 0.15), (got, expected)
    assert [r["effect"] for r in out["ranking"] if r["significant"]] == ["cable_joint_coulomb_friction"]


def test_same_record_without_friction_calls_nothing(tmp_path):
    case = cases_suspended.stopping_case(3, fs=0.0)
    rec, ds, out = _diagnose(case, tmp_path / "bag")
    assert not [r["effect"] for r in out["ranking"] if r["significant"]]


def test_rest_mask_turning_points_are_not_rests():
    # a decaying swing at 0.5 Hz with noise on its speed: never at rest, however slow it turns
    t = np.arange(0, 60, 0.01)
    rng = np.random.default_rng(0)
    qd = (0.6 * np.exp(-t / 20) * np.cos(np.pi * t))[:, None] * [1, 0.8, 0] + rng.normal(0, 2e-3, (len(t), 3))
    excited = np.array([True, True, False])
    assert not rest_mask(t, qd, excited, period=2.0).any()
    # the same swing stopped dead at 15 s: rest from there on (the window edges included)
    qd[t >= 15, :2] = rng.normal(0, 2e-3, (int(np.sum(t >= 15)), 2))
    rest = rest_mask(t, qd, excited, period=2.0)
    assert rest[t >= 15.5].all() and not rest[t < 14.5].any()
