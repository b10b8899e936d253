"""Ambiguity is a result (diagnose/ambiguity.py): two candidates that explain the same residual
within noise are flagged ``ambiguous_with`` each other, and greedy says it chose; candidates that
explain different parts of the residual are not flagged, even when they gain alike.

Oracle: constructed regressions on a toy plant whose columns are known: identical columns give a
canonical correlation of 1 and the same held-out prediction; orthogonal columns give 0."""
import numpy as np
import pytest

from cablelab.dataset import Dataset
from cablelab.diagnose import greedy, rank_candidates
from cablelab.diagnose.ambiguity import canonical_correlation, paired_log_spread, project_out
from cablelab.diagnose.result import Step, ambiguity_lines
from cablelab.effects import register
from cablelab.effects.base import Effect, Param
from cablelab.model import Model

PLANT = "toy_ambiguity"           # not a registered plant: these effects touch no real plant
T = np.arange(0.0, 30.0, 0.005)


def _sig(name):
    return lambda ds: ds.require_signal(name).reshape(ds.n, 1, 1)


def _effect(eid, signal, pname):
    return register(Effect(id=eid, plants=(PLANT,), params=(Param(pname, "N", 0.0),),
                           explanation=f"toy {eid}", signature=f"toy {eid}", reference="test",
                           regressor=_sig(signal)))


_effect("toy_base", "u", "a")
_effect("toy_twin_a", "h", "b")
_effect("toy_twin_b", "h2", "c")       # the same column as toy_twin_a, another name
_effect("toy_other", "g", "d")
_effect("toy_idle", "z", "e")


def _dataset(y_of, seed=0):
    rng = np.random.default_rng(seed)
    u = np.sin(2 * np.pi * 0.3 * T)
    h = np.tanh(5 * np.sin(2 * np.pi * 0.7 * T + 0.4))
    g = np.sin(2 * np.pi * 1.9 * T) * np.cos(2 * np.pi * 0.11 * T)
    z = rng.normal(size=T.size)                                   # explains nothing
    y = y_of(u, h, g) + 0.05 * rng.normal(size=T.size)
    return Dataset(plant=PLANT, t=T, y=y[:, None], channels=("f",), units=("N",),
                   signals={"u": u, "h": h, "h2": h.copy(), "g": g, "z": z})


def test_canonical_correlation_and_projection_closed_forms():
    rng = np.random.default_rng(1)
    a = rng.normal(size=(500, 2))
    assert canonical_correlation(a, a @ np.array([[1.0], [2.0]])) == pytest.approx(1.0, abs=1e-9)
    q, _ = np.linalg.qr(rng.normal(size=(500, 3)))
    assert canonical_correlation(q[:, :1], q[:, 1:]) == pytest.approx(0.0, abs=1e-9)
    # a column that differs from another only by a part the model already has: collinear once
    # that part is projected out
    base, x = q[:, :1], q[:, 1:2]
    assert canonical_correlation(x + base, x - 3 * base) < 0.9
    assert canonical_correlation(project_out(base, x + base), project_out(base, x - 3 * base)) \
        == pytest.approx(1.0, abs=1e-9)
    assert canonical_correlation(a, np.zeros((500, 0))) == 0.0


def test_paired_spread_is_zero_for_identical_predictions_and_sees_a_real_difference():
    rng = np.random.default_rng(2)
    y = rng.normal(size=(4000, 1))
    yh = y + 0.3 * rng.normal(size=(4000, 1))
    d, sd = paired_log_spread(y, yh, y, yh.copy())
    assert d == 0.0 and sd == 0.0
    worse = y + 0.6 * rng.normal(size=(4000, 1))
    d, sd = paired_log_spread(y, yh, y, worse)
    assert d == pytest.approx(np.log(0.3 / 0.6), abs=0.05) and abs(d) > 10 * sd


def test_identical_columns_are_ambiguous_and_greedy_says_it_chose():
    ds = _dataset(lambda u, h, g: 2.0 * u + 0.5 * h)
    model = Model(PLANT, ("toy_base",))
    d = rank_candidates(model, ds, ["toy_twin_a", "toy_twin_b", "toy_other", "toy_idle"])
    by = {r.effect: r for r in d.ranking}
    assert by["toy_twin_a"].significant and by["toy_twin_b"].significant
    assert by["toy_twin_a"].ambiguous_with == ["toy_twin_b"]
    assert by["toy_twin_b"].ambiguous_with == ["toy_twin_a"]
    assert by["toy_twin_a"].ambiguity["toy_twin_b"]["collinearity"] == pytest.approx(1.0, abs=1e-9)
    assert "ambiguous" in by["toy_twin_a"].explanation
    assert by["toy_other"].ambiguous_with is None and by["toy_idle"].ambiguous_with is None
    assert "ambiguous_with" not in by["toy_other"].to_json()
    lines = ambiguity_lines(d.ranking)
    assert len(lines) == 1 and "toy_twin_a" in lines[0] and "toy_twin_b" in lines[0]
    steps = greedy(model, ds, ["toy_twin_a", "toy_twin_b", "toy_other"])
    assert steps[1].added in ("toy_twin_a", "toy_twin_b")
    assert "chose" in steps[1].note and "cannot tell" in steps[1].note
    # the note is in the JSON
    assert isinstance(steps[1], Step) and steps[1].to_json()["note"] == steps[1].note


def test_separable_candidates_that_gain_alike_are_not_ambiguous():
    # two different missing terms of about the same size: each candidate removes a similar share
    # of the error, but with a different correction (orthogonal columns)
    ds = _dataset(lambda u, h, g: 2.0 * u + 0.35 * h + 0.5 * g)
    d = rank_candidates(Model(PLANT, ("toy_base",)), ds, ["toy_twin_a", "toy_other"])
    by = {r.effect: r for r in d.ranking}
    assert by["toy_twin_a"].significant and by["toy_other"].significant
    assert by["toy_twin_a"].ambiguous_with is None and by["toy_other"].ambiguous_with is None
    steps = greedy(Model(PLANT, ("toy_base",)), ds, ["toy_twin_a", "toy_other"])
    assert [s.added for s in steps[1:]] and all("note" not in s.to_json() for s in steps)
