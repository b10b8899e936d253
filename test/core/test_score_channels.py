"""The diagnosis score counts a channel by its own evidence (issue 10, "channels of unequal
weight") and the effective sample size of a low-passed residual is the spectral one.

Oracles: the equivalent noise bandwidth of a Butterworth filter, integrated numerically from its
frequency response (scipy.signal.freqz), for ``n_eff = 2 B n / fs`` of filtered white noise; a
six-channel linear model whose one-channel effect and blocked cross-validation are written here
with numpy least squares (not the fitting code); controls with coloured noise on every channel
whose false-significance rate must stay at the test level.
"""
from types import SimpleNamespace

import numpy as np
import pytest
import scipy.signal

from cablelab.diagnose.score import effective_sample_size, lr_significance, significant

FS = 100.0


def _enbw(b, a, fs=FS) -> float:
    """One-sided equivalent noise bandwidth, Hz: int_0^{fs/2} |H|^2 df / |H(0)|^2."""
    f, h = scipy.signal.freqz(b, a, worN=1 << 17, fs=fs)
    return float(np.trapezoid(np.abs(h) ** 2, f) / np.abs(h[0]) ** 2)


def _coloured(rng, n, channels, fc=2.0, order=2):
    b, a = scipy.signal.butter(order, fc / (FS / 2))
    return scipy.signal.lfilter(b, a, rng.standard_normal((n + 1000, channels)), axis=0)[1000:]


@pytest.mark.parametrize("order,fc", [(1, 2.0), (2, 2.0), (2, 10.0), (4, 5.0)])
def test_n_eff_of_filtered_white_noise_is_its_noise_bandwidth_count(order, fc):
    n = 4000
    b, a = scipy.signal.butter(order, fc / (FS / 2))
    oracle = 2.0 * _enbw(b, a) * n / FS
    rng = np.random.default_rng(order * 100 + int(fc))
    x = scipy.signal.lfilter(b, a, rng.standard_normal((n + 1000, 40)), axis=0)[1000:]
    est = effective_sample_size(x)                  # 40 independent channels at once
    assert np.median(est) == pytest.approx(oracle, rel=0.15)
    # the AR(1) formula n (1 - r1) / (1 + r1) it replaces is far too pessimistic for order >= 2
    r1 = np.sum(x[1:] * x[:-1], axis=0) / np.sum(x * x, axis=0)
    if order >= 2 and fc <= 5.0:
        assert np.median(n * (1 - r1) / (1 + r1)) < 0.5 * oracle


def test_n_eff_of_white_noise_is_n_and_nyquist_cap():
    x = np.random.default_rng(1).standard_normal((5000, 8))
    assert np.median(effective_sample_size(x)) == pytest.approx(5000, rel=0.15)
    assert np.all(effective_sample_size(x, step=25) <= 200.0)


def _problem(rng, theta, n=3000, channel=0, fc=2.0):
    """Six channels of a smooth signal plus unequal coloured noise; the effect ``theta * u`` acts
    on one channel only, u a smooth excitation."""
    t = np.arange(n) / FS
    u = np.sin(2 * np.pi * 0.13 * t) + 0.6 * np.sin(2 * np.pi * 0.41 * t + 1.0)
    signal = np.stack([np.sin(2 * np.pi * 0.07 * (c + 1) * t + c) for c in range(6)], axis=1) * 2.0
    scale = np.array([1.0, 0.3, 0.1, 0.5, 2.0, 0.05])
    noise = _coloured(rng, n, 6, fc) * scale / 0.15      # ~rms `scale` (filtered std ~0.15)
    y = signal * scale * 5 + noise
    y[:, channel] += theta * u * scale[channel]
    return y, signal * scale * 5, u


def _fit_cv(y, known, u, channel, folds=5):
    """Full-record and blocked-CV held-out residuals of the model ``known + k u`` on ``channel``
    (k by least squares), the other channels ``known``: the candidate; the base is ``known``."""
    n = len(y)
    r0 = y - known
    k = np.dot(u, r0[:, channel]) / np.dot(u, u)
    r1 = r0.copy()
    r1[:, channel] -= k * u
    held = r0.copy()
    edges = np.linspace(0, n, folds + 1).astype(int)
    guard = n // 100
    for i in range(folds):
        a, b = edges[i], edges[i + 1]
        tr = np.r_[0:max(a - guard, 0), min(b + guard, n):n]
        kf = np.dot(u[tr], r0[tr, channel]) / np.dot(u[tr], u[tr])
        held[a:b, channel] -= kf * u[a:b]
    rms_y = np.sqrt(np.mean(y**2, axis=0))
    nrmse0 = np.sqrt(np.mean(r0**2, axis=0)) / rms_y
    nrmse1 = np.sqrt(np.mean(held**2, axis=0)) / rms_y
    base = SimpleNamespace(residual=r0, params={"a": 0.0}, fixed=(), extra={})
    cand = SimpleNamespace(residual=r1, params={"a": 0.0, "k": k}, fixed=(), extra={})
    return base, cand, nrmse0, nrmse1, k


def test_one_channel_effect_among_six_is_significant_with_its_gain():
    found = 0
    for seed in range(10):
        rng = np.random.default_rng(seed)
        y, known, u = _problem(rng, theta=1.2)
        base, cand, n0, n1, k = _fit_cv(y, known, u, channel=0)
        sig = lr_significance(base, cand, n_candidates=6)
        ok, detail = significant(sig, n0, n1, n_candidates=6)
        gain0 = 1 - n1[0] / n0[0]
        # the effect is diluted in the geometric mean: the old 5 %-of-the-mean rule misses it
        assert detail["gain"] < 0.05 and gain0 > 0.12
        assert detail["channel_gain"][0] == pytest.approx(gain0)
        assert k == pytest.approx(1.2, rel=0.2)
        found += ok and detail["by"] == "channel" and detail["best_channel"] == 0
    assert found == 10


def test_coloured_noise_control_on_six_channels_is_not_significant():
    false, small_p = 0, 0
    seeds = range(300)
    for seed in seeds:
        rng = np.random.default_rng(1000 + seed)
        channel = seed % 6
        y, known, u = _problem(rng, theta=0.0, channel=channel, n=2000)
        base, cand, n0, n1, _ = _fit_cv(y, known, u, channel)
        sig = lr_significance(base, cand, n_candidates=1)
        false += significant(sig, n0, n1, n_candidates=1)[0]
        small_p += sig["p_value"] < 0.05
    assert false / len(seeds) <= 0.02
    # the spectral n_eff keeps the LR test near its level on 2 Hz-filtered noise, neither
    # anti-conservative (naive n) nor useless (AR(1): p < 0.05 would almost never happen)
    assert 0.01 <= small_p / len(seeds) <= 0.10


def _sig(channel_p, passes=True):
    return {"passes": passes, "channel_p": np.asarray(channel_p, float)}


def test_rule_needs_the_joint_test_the_channel_level_and_no_channel_much_worse():
    before = np.array([0.10, 0.10, 0.10, 0.10, 0.10, 0.10])
    after = np.array([0.08, 0.10, 0.10, 0.10, 0.10, 0.10])       # 20 % on one channel, 3.7 % mean
    p = [1e-6, 0.5, 0.5, 0.5, 0.5, 0.5]
    ok, d = significant(_sig(p), before, after, n_candidates=5)
    assert ok and d["by"] == "channel" and d["best_channel"] == 0
    assert d["gain"] == pytest.approx(1 - 0.8 ** (1 / 6))
    assert not significant(_sig(p, passes=False), before, after, n_candidates=5)[0]
    # the channel's own p must pass alpha / (m C) = 0.01 / 30, not only alpha / m
    assert not significant(_sig([1e-3] + p[1:]), before, after, n_candidates=5)[0]
    # another channel 3 % worse on held-out data: trading misfit, not significant; 0.5 %: fine
    worse = after.copy()
    worse[3] = 0.103
    assert not significant(_sig(p), before, worse, n_candidates=5)[0]
    worse[3] = 0.1005
    assert significant(_sig(p), before, worse, n_candidates=5)[0]
    # a channel without a signal (NaN) does not count, neither as evidence nor as a channel
    ok, d = significant(_sig([1e-6, 0.5, 0.5, 0.5, 0.5, np.nan]), np.r_[before[:5], np.nan],
                        np.r_[after[:5], np.nan], n_candidates=5)
    assert ok and d["gain"] == pytest.approx(1 - 0.8 ** (1 / 5))
    # one channel: the rule is the plain 5 % of its NRMSE
    assert not significant(_sig([1e-9]), [0.1], [0.0960])[0]
    assert significant(_sig([1e-9]), [0.1], [0.0940])[0]
