"""Single / double pendulum baselines (spec 3.2) against closed forms, and their fit."""
import numpy as np
import pytest

from cablelab.plants.suspended.baselines import fit_baseline, simulate_baseline
from cablelab.plants.suspended.identify import Experiment
from cablelab.plants.suspended.params import parameter_set


def _period(t, x):
    x = x - x.mean()
    z = np.where((x[:-1] < 0) & (x[1:] >= 0))[0]
    tz = t[z] - x[z] * (t[z + 1] - t[z]) / (x[z + 1] - x[z])
    return float(np.diff(tz).mean())


def _exp(q0, T=12.0):
    n = int(T * 100)
    return Experiment("e", np.arange(n) * 0.01, np.zeros((n, 3)), q0, T, 10)


def test_single_pendulum_period_closed_form_and_fit_recovers_length():
    p = parameter_set("licas")
    th0 = 0.1
    e = _exp({"J8": th0})
    y = simulate_baseline("single", p, [e], [{"l": 1.3, "c": 0.0}])[0][0]
    T = 2 * np.pi * np.sqrt(1.3 / 9.81) * (1 + th0 ** 2 / 16)
    assert _period(e.t, y[:, 1]) == pytest.approx(T, rel=2e-3)
    # output is the point at L along the rod: amplitude L sin(th0)
    assert np.abs(y[:, 1]).max() == pytest.approx(p.L * np.sin(th0), rel=1e-3)
    # fit to data of a damped 1.1 m pendulum recovers l and c
    y_true = simulate_baseline("single", p, [e], [{"l": 1.1, "c": 0.3}])[0][0]
    e_meas = Experiment("m", e.t, y_true + np.random.default_rng(0).normal(0, 1e-3, y_true.shape),
                        e.q0, e.duration, 10, None, np.array([False, True, False]))
    vals, _ = fit_baseline("single", p, [e_meas])
    assert vals["l"] == pytest.approx(1.1, rel=0.01) and vals["c"] == pytest.approx(0.3, rel=0.1)


def test_double_pendulum_without_tilt_coupling_has_two_modes():
    p = parameter_set("licas")
    e = _exp({"J8": 0.05}, 20.0)
    y = simulate_baseline("double", p, [e], [{"c1": 0.0, "c2": 0.0}])[0][0]
    spec = np.abs(np.fft.rfft(y[:, 1] - y[:, 1].mean()))
    f = np.fft.rfftfreq(len(e.t), 0.01)
    # the slow (pendulum) mode near 1/(2 pi) sqrt(g / (L + c_p)) dominates
    f0 = f[np.argmax(spec)]
    assert 0.35 < f0 < 0.55
