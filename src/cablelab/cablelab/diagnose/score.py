"""The diagnosis score: per-channel, noise-weighted, and honest about coloured residuals.

* Held-out error (:func:`heldout_error`): the geometric mean over channels of the per-channel
  NRMSE, ``exp(mean_c log(rms(e_c) / rms(y_c)))``. Up to constants, ``2 C log`` of it is the
  held-out Gaussian negative log-likelihood with a separate (profiled) variance per channel, so a
  channel counts by its relative improvement, not by its share of the pooled error. It is the
  ranking score; the per-channel NRMSE stays in the output for humans.
* Effective sample size (:func:`effective_sample_size`): ``n_eff,c = n / tau_c`` with the
  integrated autocorrelation time ``tau_c = 1 + 2 sum_k rho_c(k)`` of the channel's residual,
  summed by Geyer's initial positive sequence (pairs ``rho(2k) + rho(2k+1)`` while positive;
  Geyer 1992, Stat. Sci. 7(4), eq. 3.2 ff.). ``n / tau`` is ``n`` times the spectral flatness
  ``mean(S) / S(0)``: the number of independent samples a low-frequency regressor sees in the
  residual (for white noise through a filter H it is ``2 B n / fs``, B the filter's equivalent
  noise bandwidth). The AR(1) formula ``n (1 - r1) / (1 + r1)`` it replaces is right only for a
  first-order process; for a residual low-passed at 2 Hz of 100 Hz data (a smooth, second-order
  or higher process, ``1 - r1 ~ (f_c / fs)^2``) it gave 12 of 1338 samples where the spectrum
  gives ~60. On a parallel-filtered dataset it is further capped at the Nyquist count
  ``n / step`` (:func:`~cablelab.fit.identify.sample_step`). The test uses the larger of this
  and the AR(1) count (:func:`significance_samples`): while another effect is still missing, its
  slow deterministic signature in the residual is not noise correlation.
* Significance (:func:`lr_significance`, :func:`significant`): the Gaussian likelihood-ratio
  statistic with a variance per channel, ``LR_c = n_eff,c log(RSS0_c / RSS1_c)`` per channel and
  ``LR = sum_c LR_c`` ~ chi^2(dp) under "no gain" (Wilks). A candidate is significant when the
  joint LR rejects at ``alpha / m`` (Bonferroni over the m candidates) and the held-out error
  falls by ``MIN_GAIN`` (5 %) *either* in the geometric mean *or* on one channel by that
  channel's own evidence: its held-out NRMSE falls by ``MIN_GAIN`` and its own LR rejects at
  ``alpha / (m C)`` (Bonferroni over candidates x channels), while the geometric mean does not
  get worse and no channel's held-out NRMSE rises by more than ``OTHER_LOSS * MIN_GAIN`` (1 %):
  an effect that acts on one channel leaves the others alone, one that gains on one channel by
  losing on another trades model misfit between them. An effect that acts
  on one channel of six (a CDPR tension delay seen in Fz, ``platform_inertia``) is thereby not
  diluted by the five channels that do not care: it needs 5 % on its channel, not ~27 %.
  The BIC difference on the effective samples is reported alongside.
"""
from __future__ import annotations

import numpy as np
import scipy.stats

#: on the one-channel route, the largest held-out loss of any channel, as a fraction of MIN_GAIN
OTHER_LOSS = 0.2
#: a channel residual below this rms (in its unit) under both fits is round-off, not information
ROUND_OFF_RMS = 1e-12


def channel_nrmse(y: np.ndarray, y_hat: np.ndarray, valid: np.ndarray | None = None) -> np.ndarray:
    """(C,) rms(y - y_hat) / rms(y) per channel over the finite, valid rows."""
    y = np.asarray(y, float).reshape(len(y), -1)
    y_hat = np.asarray(y_hat, float).reshape(y.shape)
    ok = np.isfinite(y).all(axis=1) & np.isfinite(y_hat).all(axis=1)
    if valid is not None:
        ok &= np.asarray(valid, bool)
    e = y[ok] - y_hat[ok]
    rms_y = np.sqrt(np.mean(y[ok] ** 2, axis=0))
    # a channel that is identically zero (set aside by its plant as not excited) has no NRMSE
    return np.where(rms_y > 0, np.sqrt(np.mean(e**2, axis=0)) / np.where(rms_y > 0, rms_y, 1.0),
                    np.nan)


def heldout_error(y: np.ndarray, y_hat: np.ndarray, valid: np.ndarray | None = None) -> float:
    """Geometric mean over the channels with a signal of the per-channel NRMSE (see module doc)."""
    c = channel_nrmse(y, y_hat, valid)
    c = c[np.isfinite(c)]
    return float(np.exp(np.mean(np.log(np.maximum(c, 1e-300))))) if c.size else 0.0


def autocorrelation_time(residual: np.ndarray) -> np.ndarray:
    """(C,) integrated autocorrelation time ``tau = 1 + 2 sum_{k>=1} rho(k)`` of each column of a
    residual (N,) or (N, C) (rows with a NaN dropped), by Geyer's initial positive sequence: the
    pair sums ``Gamma_j = rho(2j) + rho(2j+1)`` are added while positive (for a stationary
    process they are positive and decreasing; the first non-positive one marks where the
    estimate becomes noise). Autocorrelation by FFT, vectorised over channels; ``tau >= 1``."""
    r = np.asarray(residual, dtype=float)
    r = r.reshape(r.shape[0], -1)
    r = r[np.isfinite(r).all(axis=1)]
    n, c = r.shape
    if n < 4:
        return np.ones(c)
    r = r - r.mean(axis=0)
    nfft = 1 << int(np.ceil(np.log2(2 * n)))
    f = np.fft.rfft(r, nfft, axis=0)
    acov = np.fft.irfft(f * np.conj(f), nfft, axis=0)[:n]
    var = acov[0]
    rho = np.where(var > 0, acov / np.where(var > 0, var, 1.0), 0.0)
    m = n // 2
    gam = rho[0:2 * m:2] + rho[1:2 * m:2]                  # (m, C) Gamma_0, Gamma_1, ...
    positive = np.cumprod(gam > 0, axis=0).astype(bool)    # initial positive run
    # tau = -1 + 2 sum_j Gamma_j (Gamma_0 = 1 + rho(1))
    tau = -1.0 + 2.0 * np.sum(np.where(positive, gam, 0.0), axis=0)
    return np.where(var > 0, np.maximum(tau, 1.0), 1.0)


def effective_sample_size(residual: np.ndarray, step: int = 1) -> np.ndarray:
    """(C,) effective number of independent samples ``n / tau`` of each column of a residual
    (:func:`autocorrelation_time`), at most the Nyquist count ``n / step`` of a parallel-filtered
    dataset and at least 3. For white noise through a filter H at rate fs it is ``2 B n / fs``,
    B = ``int_0^{fs/2} |H(f)|^2 df / |H(0)|^2`` the equivalent noise bandwidth."""
    r = np.asarray(residual, dtype=float)
    r = r.reshape(r.shape[0], -1)
    n = int(np.isfinite(r).all(axis=1).sum())
    n_eff = n / autocorrelation_time(r)
    return np.clip(n_eff, 3.0, max(n / max(1, int(step)), 3.0))


def significance_samples(residual: np.ndarray, step: int = 1) -> np.ndarray:
    """(C,) effective samples of each channel for the significance test: the larger of the
    spectral count (:func:`effective_sample_size`) and the AR(1) count at lag ``step``
    (:func:`~cablelab.fit.identify.effective_samples`, the previous rule).

    The spectral count is right when the residual is noise. While a second effect is still
    missing, the residual also carries that effect's deterministic signature (steps at every
    reversal for Coulomb friction, a constant for an offset), whose slow "correlation" is model
    misfit, not noise: it made n_eff 5 of 9900 samples at 1 kHz (axis, Coulomb + offset hidden,
    first greedy step). The lag-``step`` AR(1) count reads the noise's short-range correlation and
    is not fooled by a slow misfit; for a smooth low-passed noise it is the smaller one (the
    spectral count then applies). Both are validated on the controls of the benchmark."""
    from ..fit.identify import effective_samples

    r = np.asarray(residual, dtype=float)
    r = r.reshape(r.shape[0], -1)
    ar1 = np.array([effective_samples(r[:, c], step) for c in range(r.shape[1])])
    return np.maximum(effective_sample_size(r, step), ar1)


def _n_free(ident) -> int:
    return len(ident.params) - len(ident.fixed)


def lr_significance(base, cand, n_candidates: int = 1, alpha: float = 0.01) -> dict:
    """Per-channel Gaussian likelihood-ratio test of a candidate fit against the base fit.

    Args:
        base, cand: :class:`~cablelab.fit.Identification` without / with the effect (full record).
    Returns:
        ``{"p_value", "lr", "n_eff", "delta_bic", "passes", "channel_lr", "channel_p",
        "channel_n_eff"}``: the joint test (passes: p < alpha / n_candidates) and, per channel
        (NaN for a round-off channel), each channel's own LR, p-value and effective samples.
    """
    ok = np.isfinite(base.residual).all(axis=1) & np.isfinite(cand.residual).all(axis=1)
    r0, r1 = base.residual[ok], cand.residual[ok]
    n, n_ch = r1.shape
    rss0 = np.sum(r0**2, axis=0)
    rss1 = np.sum(r1**2, axis=0)
    # a channel whose residual is round-off under both fits (a channel the dataset zeroes where it
    # is not excited, e.g. the suspended yaw) carries no information; its log ratio of two
    # round-offs would swamp the test either way
    live = np.sqrt(np.maximum(rss0, rss1) / max(n, 1)) > ROUND_OFF_RMS
    if not live.any():
        live[:] = True
    step = int(cand.extra.get("sample_step", 1))  # parallel-filtered data: fs / (2 f_c)
    n_eff = np.full(n_ch, np.nan)
    n_eff[live] = significance_samples(r1[:, live], step)
    dp = max(_n_free(cand) - _n_free(base), 1)
    with np.errstate(divide="ignore", invalid="ignore"):
        lr_c = np.where(live, n_eff * np.log(np.maximum(rss0, 1e-300) / np.maximum(rss1, 1e-300)),
                        np.nan)
    lr = float(np.nansum(lr_c))
    p_value = float(scipy.stats.chi2.sf(lr, dp)) if np.isfinite(lr) else 0.0
    p_c = np.where(live, scipy.stats.chi2.sf(np.where(np.isfinite(lr_c), lr_c, 0.0), dp), np.nan)
    p_c = np.where(live & ~np.isfinite(lr_c) & (lr_c > 0), 0.0, p_c)
    n_mean = float(np.nanmean(n_eff))
    return {"p_value": p_value, "lr": lr, "n_eff": n_mean, "delta_bic": -lr + dp * np.log(n_mean),
            "passes": bool(p_value < alpha / max(n_candidates, 1)),
            "channel_lr": lr_c, "channel_p": p_c, "channel_n_eff": n_eff}


def significant(sig: dict, nrmse_before, nrmse_after, n_candidates: int = 1, alpha: float = 0.01,
                min_gain: float = 0.05) -> tuple[bool, dict]:
    """The significance rule of the module doc: joint LR, and the held-out gain in the geometric
    mean or on one channel by that channel's own LR.

    Args:
        sig: :func:`lr_significance` of the candidate; nrmse_before / nrmse_after: (C,) held-out
            per-channel NRMSE of the model without / with it (NaN: channel without a signal).
    Returns:
        ``(significant, detail)``; detail ``{"gain", "channel_gain", "best_channel", "by"}``:
        the geometric-mean gain, the per-channel gains (NaN where undefined), the index of the
        channel that carries the evidence (or None) and ``"mean"`` / ``"channel"`` / None.
    """
    b = np.asarray(nrmse_before, float)
    a = np.asarray(nrmse_after, float)
    both = np.isfinite(b) & np.isfinite(a) & (b > 0)
    with np.errstate(divide="ignore", invalid="ignore"):
        g_c = np.where(both, 1.0 - a / np.where(b > 0, b, 1.0), np.nan)
    if both.any():
        gm = 1.0 - float(np.exp(np.mean(np.log(np.maximum(a[both], 1e-300) / b[both]))))
    else:
        gm = 0.0
    detail = {"gain": gm, "channel_gain": g_c, "best_channel": None, "by": None}
    if not sig["passes"]:
        return False, detail
    if gm >= min_gain:
        detail["by"] = "mean"
        return True, detail
    n_live = max(int(np.sum(np.isfinite(sig["channel_p"]))), 1)
    level = alpha / (max(n_candidates, 1) * n_live)
    own = both & (g_c >= min_gain) & np.isfinite(sig["channel_p"]) & (sig["channel_p"] < level)
    # a one-channel effect leaves the other channels' held-out error alone; one that buys its gain
    # on one channel by losing more than a fifth of MIN_GAIN on another is trading model misfit
    # between channels (suspended control 5009: air drag +8.5 % swing_y, -3.0 % swing_x)
    worse = both & (g_c < -OTHER_LOSS * min_gain)
    if gm > 0 and own.any() and not worse.any():
        detail["best_channel"] = int(np.nanargmax(np.where(own, g_c, -np.inf)))
        detail["by"] = "channel"
        return True, detail
    return False, detail
