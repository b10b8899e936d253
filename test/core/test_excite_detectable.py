"""``excite.detectable_delay``: the smallest delay a recording shows, from the delay's column with
the other columns projected out, each channel in units of its noise.

Oracles: an independent least-squares projection (numpy lstsq) for the per-channel signal-to-noise
ratios; the diagnosis' two criteria written out at the returned delays (the practical gain's
geometric mean reaches MIN_GAIN; the likelihood-ratio statistic reaches the chi^2(1) quantile);
the closed form for equal channels; and a Monte Carlo fit: data made of the delay's column times
the returned delay plus Gaussian noise, fitted with and without that column, lose the diagnosis'
5 % of their RMS error."""
from types import SimpleNamespace

import numpy as np
import pytest
import scipy.stats

from cablelab import excite as E
from cablelab.diagnose.ranking import ALPHA, MIN_GAIN


class _Columns:
    """A model whose regressor is given: (N, C, P), the delay's column last."""

    def __init__(self, phi):
        self.phi = phi

    def regressor(self, ds):
        return self.phi, None, None


def _problem(n=4000, c=3, seed=0):
    rng = np.random.default_rng(seed)
    other = rng.normal(size=(n, c, 2))
    tau_col = 0.6 * other[:, :, 0] + rng.normal(size=(n, c)) * np.array([200.0, 80.0, 30.0])[:c]
    phi = np.concatenate([other, tau_col[:, :, None]], axis=2)
    ds = SimpleNamespace(t=np.arange(n) * 0.01, valid=np.ones(n, bool))
    return phi, ds


def test_snr_is_the_projected_column_over_the_noise():
    phi, ds = _problem()
    sigma = np.array([2.0, 1.0, 0.5])
    d = E.detectable_delay(_Columns(phi), ds, sigma, 50.0, n_candidates=6)
    w = phi / sigma[None, :, None]
    a, b = w[:, :, :2].reshape(-1, 2), w[:, :, 2].reshape(-1)
    resid = b - a @ np.linalg.lstsq(a, b, rcond=None)[0]
    s = np.sqrt(np.mean(resid.reshape(-1, 3) ** 2, axis=0))
    assert d["snr"] == pytest.approx(s, rel=1e-9)
    # the two criteria, written out at the delays returned
    g = 1.0 - np.exp(-0.5 * np.mean(np.log1p(d["by_gain"] ** 2 * s ** 2)))
    assert g == pytest.approx(MIN_GAIN, rel=1e-8)
    n_eff = 50.0 * (ds.t[-1] - ds.t[0])
    lr = n_eff * np.sum(np.log1p(d["by_test"] ** 2 * s ** 2))
    assert lr == pytest.approx(scipy.stats.chi2.isf(ALPHA / 6, 1), rel=1e-8)
    assert d["tau"] == max(d["by_gain"], d["by_test"])
    # a longer record lowers the test's delay, never the gain's
    longer = E.detectable_delay(_Columns(phi), ds, sigma, 500.0, n_candidates=6)
    assert longer["by_gain"] == pytest.approx(d["by_gain"], rel=1e-12)
    assert longer["by_test"] == pytest.approx(d["by_test"] / np.sqrt(10.0), rel=0.01)


def test_equal_channels_closed_form():
    rng = np.random.default_rng(3)
    n = 5000
    z = rng.normal(size=n)
    phi = np.stack([np.ones((n, 2)), np.stack([z, z], axis=1) * 40.0], axis=2)
    ds = SimpleNamespace(t=np.arange(n) * 0.01, valid=np.ones(n, bool))
    d = E.detectable_delay(_Columns(phi), ds, np.array([4.0, 4.0]), 1e4)
    s = 40.0 * np.std(z) / 4.0
    assert d["by_gain"] == pytest.approx(np.sqrt((1 - MIN_GAIN) ** -2 - 1) / s, rel=1e-6)


def test_a_fit_loses_five_percent_at_the_detectable_delay():
    phi, ds = _problem(n=20000, c=3, seed=5)
    sigma = np.array([3.0, 1.5, 1.0])
    d = E.detectable_delay(_Columns(phi), ds, sigma, 1e6)
    rng = np.random.default_rng(7)
    gains = []
    for tau in (d["by_gain"], 0.5 * d["by_gain"], 2.0 * d["by_gain"]):
        y = tau * phi[:, :, 2] + 0.3 * phi[:, :, 0] + rng.normal(size=phi.shape[:2]) * sigma
        w = 1.0 / sigma                                     # the fit's noise weights
        rms = []
        for cols in ([0, 1], [0, 1, 2]):
            a = (phi[:, :, cols] * w[None, :, None]).reshape(-1, len(cols))
            theta = np.linalg.lstsq(a, (y * w).reshape(-1), rcond=None)[0]
            rms.append(np.sqrt(np.mean((y - phi[:, :, cols] @ theta) ** 2, axis=0)))
        gains.append(1.0 - np.exp(np.mean(np.log(rms[1] / rms[0]))))
    assert gains[0] == pytest.approx(MIN_GAIN, abs=0.005)
    assert gains[1] < MIN_GAIN < gains[2]


def test_no_column_no_detection():
    n = 500
    phi = np.zeros((n, 2, 2))
    phi[:, :, 0] = 1.0
    ds = SimpleNamespace(t=np.arange(n) * 0.01, valid=np.ones(n, bool))
    assert np.isinf(E.detectable_delay(_Columns(phi), ds, np.ones(2), 100.0)["tau"])
