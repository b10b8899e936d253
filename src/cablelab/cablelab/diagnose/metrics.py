"""Comparison metrics, per output channel (000 tables 1-2, 003 eq. 28, MATLAB ``compare``).

Definitions (e = measured - model over the valid samples of one channel):

* ``nrmse`` = rms(e) / rms(y): the normalised RMS error of the EMPS reference (18 % -> 7 % -> 4 %).
* ``fit_percent`` = 100 (1 - ||e|| / ||y - mean(y)||): MATLAB's fit % (NRMSE normalised by the
  spread around the mean).
* ``nmse`` = mean(e^2) / var(y): the normalised MSE of 003 eq. 28.
* ``pearson``: correlation coefficient of y and model (000 eq. 3-7 use its mean as objective).
* ``mae`` = mean |e|; ``mre`` = sum |e| / sum |y| (mean relative error, robust to y near 0);
  ``max_abs`` = max |e|.

The simulation-fit objectives themselves (the NMSE sum of 003 eq. 28, the mean Pearson
correlation of 000 eq. 7) are :func:`cablelab.fit.simulation.objective_residual`.
"""
from __future__ import annotations

import numpy as np


def _ok(y, y_hat, valid):
    y = np.asarray(y, dtype=float)
    y_hat = np.asarray(y_hat, dtype=float)
    if y.ndim == 1:
        y, y_hat = y[:, None], y_hat[:, None]
    ok = np.isfinite(y).all(axis=1) & np.isfinite(y_hat).all(axis=1)
    if valid is not None:
        ok &= np.asarray(valid, dtype=bool)
    return y[ok], y_hat[ok]


def channel_metrics(y: np.ndarray, y_hat: np.ndarray, valid: np.ndarray | None = None) -> list[dict]:
    """Metrics per channel: ``[{nrmse, fit_percent, nmse, pearson, mae, mre, max_abs, rms, n}]``.

    Args:
        y, y_hat: (N, C) measured and model output; valid: (N,) mask.
    """
    y, yh = _ok(y, y_hat, valid)
    e = y - yh
    n = y.shape[0]
    rms_y = np.sqrt(np.mean(y**2, axis=0))
    rms_e = np.sqrt(np.mean(e**2, axis=0))
    spread = np.linalg.norm(y - y.mean(axis=0), axis=0)
    var_y = np.var(y, axis=0)
    yc, hc = y - y.mean(axis=0), yh - yh.mean(axis=0)
    den = np.sqrt(np.sum(yc**2, axis=0) * np.sum(hc**2, axis=0))
    pearson = np.where(den > 0, np.sum(yc * hc, axis=0) / np.where(den > 0, den, 1), np.nan)
    out = []
    for c in range(y.shape[1]):
        out.append({
            "nrmse": _f(rms_e[c] / rms_y[c]) if rms_y[c] > 0 else None,
            "fit_percent": _f(100.0 * (1.0 - np.linalg.norm(e[:, c]) / spread[c])) if spread[c] > 0 else None,
            "nmse": _f(np.mean(e[:, c] ** 2) / var_y[c]) if var_y[c] > 0 else None,
            "pearson": _f(pearson[c]),
            "mae": _f(np.mean(np.abs(e[:, c]))),
            "mre": _f(np.sum(np.abs(e[:, c])) / np.sum(np.abs(y[:, c]))) if np.any(y[:, c]) else None,
            "max_abs": _f(np.max(np.abs(e[:, c]))) if n else None,
            "rms": _f(rms_e[c]),
            "n": int(n),
        })
    return out


def _f(x) -> float | None:
    x = float(x)
    return x if np.isfinite(x) else None


def nrmse(y: np.ndarray, y_hat: np.ndarray, valid: np.ndarray | None = None) -> float:
    """Mean over channels of rms(e) / rms(y) (one number for rankings)."""
    y, yh = _ok(y, y_hat, valid)
    rms_y = np.sqrt(np.mean(y**2, axis=0))
    rms_e = np.sqrt(np.mean((y - yh) ** 2, axis=0))
    return float(np.mean(rms_e / np.where(rms_y > 0, rms_y, 1.0)))
