"""Effects whose output has a term beyond their linear columns (``Effect.higher_order``): the fit
evaluates it at its current estimate and refits until the estimate settles. Oracle: data made
exactly by ``y = a x + (a^2 / 2) z + b`` (a closed form the columns alone cannot represent)."""
import numpy as np
import pytest

from cablelab.dataset import Dataset
from cablelab.effects.base import Effect, Param
from cablelab.fit import identify
from cablelab.model import Model

A, B = 0.8, 0.3


def _effect(higher: bool) -> Effect:
    return Effect(id="scaled_signal", plants=("toy",), params=(Param("a", "-"),),
                  explanation="a x plus a small term quadratic in a", signature="-", reference="-",
                  regressor=lambda ds: ds.signals["x"][:, None, None],
                  higher_order=(lambda ds, v: (0.5 * v.get("a", 0.0) ** 2 * ds.signals["z"])[:, None])
                  if higher else None)


OFFSET = Effect(id="toy_offset", plants=("toy",), params=(Param("b", "-"),), explanation="offset",
                signature="-", reference="-", regressor=lambda ds: np.ones((ds.n, 1, 1)))


def _dataset(noise: float = 0.0, seed: int = 0) -> Dataset:
    rng = np.random.default_rng(seed)
    n = 600
    t = np.arange(n) * 0.01
    x = np.sin(2.1 * t) + 0.3 * rng.normal(size=n)
    z = 0.4 * np.cos(0.7 * t) + 0.2          # partly an offset: the columns would take it up
    y = A * x + 0.5 * A ** 2 * z + B + noise * rng.normal(size=n)
    return Dataset(plant="toy", t=t, y=y[:, None], channels=("out",), units=("-",),
                   signals={"x": x, "z": z})


def test_iterated_fit_recovers_the_exact_parameters():
    ds = _dataset()
    r = identify(Model("toy", (_effect(True), OFFSET)), ds)
    assert r.params["a"] == pytest.approx(A, abs=1e-7)
    assert r.params["b"] == pytest.approx(B, abs=1e-7)
    assert 2 <= r.extra["higher_order_steps"] <= 8
    assert np.nanmax(np.abs(r.residual)) < 1e-6
    # the same columns without the term: the fit is biased (what the term corrects)
    first = identify(Model("toy", (_effect(False), OFFSET)), ds)
    assert abs(first.params["b"] - B) > 1e-2
    assert "higher_order_steps" not in first.extra


def test_prediction_evaluates_the_term_at_the_given_values():
    ds = _dataset()
    model = Model("toy", (_effect(True), OFFSET))
    y, _ = model.predict(ds, {"a": A, "b": B})
    np.testing.assert_allclose(y, ds.y, atol=1e-12)
    # at the nominal values (a = 0) the term vanishes: the model's own ``at`` is empty
    phi, _, y_known = model.regressor(ds)
    assert not y_known.any()


def test_standard_error_covers_the_truth_under_noise():
    hits = 0
    for seed in range(20):
        r = identify(Model("toy", (_effect(True), OFFSET)), _dataset(noise=0.05, seed=seed))
        hits += abs(r.params["a"] - A) < 2 * r.stderr["a"]
    assert hits >= 15
