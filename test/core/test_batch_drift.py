"""The drift test of cablelab.fleet.drift against independent oracles: the step statistic equals
the squared pooled two-sample t statistic (scipy.stats.ttest_ind), the trend statistic the F test
of scipy's linregress on the hinge regressor, the family-wise false-alarm rate under the null stays
below alpha, and planted steps / trends are located."""
from __future__ import annotations

import datetime as dt

import numpy as np
import pytest
from scipy import stats

from cablelab.fleet.drift import Series, change_point, detect


def _series(y, machine="m", start_day=0):
    t0 = dt.datetime(2026, 1, 1, tzinfo=dt.timezone.utc)
    times = [t0 + dt.timedelta(days=start_day + i) for i in range(len(y))]
    return Series(machine, "e", "p", times, np.asarray(y, float), np.full(len(y), 0.1),
                  [f"b{i}" for i in range(len(y))])


def test_step_statistic_is_the_pooled_t_test_squared():
    rng = np.random.default_rng(0)
    y = rng.normal(0, 1, 12)
    y[7:] += 3.0
    cp = change_point(np.arange(12.0), y)
    assert cp.kind == "step" and cp.k == 7
    t, p = stats.ttest_ind(y[:7], y[7:], equal_var=True)
    assert cp.f == pytest.approx(t**2, rel=1e-9)
    assert cp.p_raw == pytest.approx(p, rel=1e-6)
    assert cp.p == pytest.approx(min(1.0, p * cp.tries), rel=1e-6)


def test_trend_statistic_matches_linregress_on_the_hinge():
    rng = np.random.default_rng(1)
    t = np.arange(15.0)
    y = 1.0 + 0.2 * np.maximum(0, t - 6) + rng.normal(0, 0.05, 15)
    cp = change_point(t, y)
    assert cp.kind == "trend" and cp.k == 7  # hinge at bag 6: bag 7 is the first changed
    lr = stats.linregress(np.maximum(0, t - t[cp.k - 1]), y)
    tstat = lr.slope / lr.stderr
    assert cp.f == pytest.approx(tstat**2, rel=1e-6)


def test_null_false_alarm_rate_below_alpha():
    rng = np.random.default_rng(2)
    alpha, trials = 0.05, 300
    series = [_series(rng.normal(5.0, 0.3, 10), machine=f"m{i}") for i in range(trials)]
    # one series at a time (per-series Bonferroni over change points and kinds)
    alarms = sum(detect([s], alpha)[0] != [] for s in series)
    assert alarms / trials <= alpha + 0.02
    # the whole family at once (Holm): essentially never a false alarm
    assert detect(series, alpha)[0] == []


@pytest.mark.parametrize("kind,k", [("step", 4), ("step", 8), ("trend", 5)])
def test_planted_change_is_located(kind, k):
    rng = np.random.default_rng(3)
    n = 12
    y = rng.normal(2.0, 0.02, n)
    if kind == "step":
        y[k:] += 0.3
    else:
        y += 0.04 * np.maximum(0, np.arange(n) - (k - 1))
    clean = [_series(rng.normal(2.0, 0.02, n), machine=f"c{i}") for i in range(5)]
    findings, tests = detect([_series(y, machine="bad")] + clean, 0.01)
    assert [f.machine for f in findings] == ["bad"]
    f = findings[0]
    assert f.kind == kind and abs((f.since - _series(y).time[k]).days) <= 1


def test_constant_and_short_series_are_not_tested():
    assert change_point(np.arange(10.0), np.full(10, 3.0)) is None
    assert change_point(np.arange(3.0), np.array([1.0, 2.0, 3.0])) is None
