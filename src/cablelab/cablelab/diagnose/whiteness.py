"""Residual whiteness and cross-correlation with inputs, with confidence bands (as MATLAB's
``resid``): a correct model leaves a residual that is white and uncorrelated with the inputs.
Under that hypothesis the normalised correlations at non-zero lags are ~N(0, 1/N); the band is
``z / sqrt(N)`` (z = 2.58 for 99 %, drawn in the report). The verdicts ``white`` and
``uncorrelated`` use the family-wise band over all L lags examined (Bonferroni:
z = Phi^-1(1 - 0.01 / (2 L))), so one chance excursion in 50 lags does not flag a good model but
any real correlation does.
"""
from __future__ import annotations

import numpy as np
import scipy.stats

#: lags examined (samples), as MATLAB resid's default
MAX_LAG = 25
#: two-sided 99 % normal quantile
Z99 = 2.576


def _xcorr(a: np.ndarray, b: np.ndarray, max_lag: int) -> np.ndarray:
    """Normalised cross-correlation r_ab(k) = sum a(t+k) b(t) / (N sa sb), k = -L..L (FFT)."""
    a = a - a.mean()
    b = b - b.mean()
    n = a.size
    nfft = 1 << int(np.ceil(np.log2(2 * n)))
    fa, fb = np.fft.rfft(a, nfft), np.fft.rfft(b, nfft)
    full = np.fft.irfft(fa * np.conj(fb), nfft)
    lags = np.arange(-max_lag, max_lag + 1)
    r = full[lags % nfft]
    den = np.sqrt(np.sum(a * a) * np.sum(b * b))
    return r / den if den > 0 else np.zeros_like(r)


def whiteness(residual: np.ndarray, inputs: dict[str, np.ndarray] | None = None, *,
              max_lag: int = MAX_LAG, z: float = Z99, decimate: int = 1) -> dict:
    """Autocorrelation of a residual channel and its cross-correlation with inputs.

    Args:
        residual: (N,) residual (NaN samples dropped, with the same rows of the inputs).
        inputs: name -> (N,) input signals.
        decimate: test every k-th sample only. A residual of low-pass-filtered signals (cut-off
            f_c) is coloured below f_c even when the model is exact; at k = fs / (2 f_c) its
            samples are (nearly) independent again, so the test is valid on filtered data
            (tested on every sample, the filtered residual of a correct model is called not
            white). The cross-correlation band is Bartlett's
            ``z sqrt(sum_j rho_rr(j) rho_uu(j) / N)``, valid for a coloured input.
    Returns:
        ``{"band", "lags", "autocorr", "white", "outside", "cross": {name: {"xcorr",
        "outside", "uncorrelated"}}}``; ``outside`` = fraction of lags (excluding 0 for the
        autocorrelation) beyond the band.
    """
    inputs = inputs or {}
    ok = np.isfinite(residual)
    for v in inputs.values():
        ok &= np.isfinite(v)
    k = max(1, int(decimate))
    r = residual[ok][::k]
    n = r.size
    max_lag = int(min(max_lag, max(1, n // 4)))
    band = z / np.sqrt(max(n, 1))
    lags = np.arange(-max_lag, max_lag + 1)
    ac = _xcorr(r, r, max_lag)
    pos = ac[max_lag + 1:]
    fw = float(scipy.stats.norm.ppf(1 - 0.01 / (2 * max_lag)) / np.sqrt(max(n, 1)))
    m_b = int(min(4 * max_lag, max(1, n // 4)))
    ac_b = _xcorr(r, r, m_b)
    out = {"band": float(band), "band_familywise": fw, "lags": lags[max_lag:].tolist(), "decimate": k,
           "autocorr": ac[max_lag:].tolist(), "outside": float(np.mean(np.abs(pos) > band)),
           "white": bool(np.max(np.abs(pos)) <= fw), "cross": {}}
    fw_x = float(scipy.stats.norm.ppf(1 - 0.01 / (2 * lags.size)) / np.sqrt(max(n, 1)))
    for name, u in inputs.items():
        uk = np.asarray(u)[ok][::k]
        xc = _xcorr(r, uk, max_lag)
        bart = float(np.sqrt(max(np.sum(ac_b * _xcorr(uk, uk, m_b)), 1.0)))  # Bartlett factor
        out["cross"][name] = {"lags": lags.tolist(), "xcorr": xc.tolist(), "bartlett": bart,
                              "outside": float(np.mean(np.abs(xc) > band * bart)),
                              "uncorrelated": bool(np.max(np.abs(xc)) <= fw_x * bart)}
    return out
