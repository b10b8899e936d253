"""The diagnosis score: per-channel, noise-weighted, and honest about coloured residuals.

* Held-out error (:func:`heldout_error`): the geometric mean over channels of the per-channel
  NRMSE, ``exp(mean_c log(rms(e_c) / rms(y_c)))``. Up to constants, ``2 C log`` of it is the
  held-out Gaussian negative log-likelihood with a separate (profiled) variance per channel, so a
  channel counts by its relative improvement, not by its share of the pooled error: a 40 %
  drop on the one channel an effect acts on (CDPR Fz and ``platform_inertia``) is not averaged
  away by five channels that do not care. One channel: the plain NRMSE.
  The per-channel NRMSE stays in the output for humans.
* Practical gain (:func:`practical_gain`): the relative drop of that geometric mean over the
  channels whose held-out prediction the candidate changes at all. A channel an effect cannot
  touch (a CDPR winch's torque balance under ``pulley_geometry`` or ``time_delay``: its prediction
  stays exactly what it was) neither helps nor dilutes it: with ``--tensions both`` eight such
  noise channels beside the six wrench channels cut a wrench effect's gain to 6/14 of itself.
  When a candidate changes every channel this is the plain relative drop of the held-out error.
* Significance (:func:`lr_significance`): the Gaussian likelihood-ratio statistic with a variance
  per channel, ``LR = sum_c n_eff,c log(RSS0_c / RSS1_c)`` ~ chi^2(dp) under "no gain" (Wilks),
  where ``n_eff,c = n (1 - r1_c) / (1 + r1_c)`` is the AR(1) effective sample size of the
  channel's residual (a filtered, oversampled residual is far from white; on a parallel-filtered
  dataset it is taken every fs / (2 f_c) samples, :func:`~cablelab.fit.identification.sample_step`),
  tested at
  ``alpha / m`` for the m candidates tried (Bonferroni). The BIC difference on the same
  effective samples is reported alongside.
"""
from __future__ import annotations

import numpy as np
import scipy.stats

from ..fit.identification import effective_samples

#: default significance level of the likelihood-ratio test
ALPHA = 0.01
#: minimum relative reduction of the held-out error for an effect to count as significant
MIN_GAIN = 0.05


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


#: a channel counts as changed by a candidate when its held-out prediction moves by more than this
#: share of the channel's rms somewhere (refits leave untouched channels equal to round-off)
CHANGE_TOL = 1e-6


def changed_channels(y: np.ndarray, y_hat0: np.ndarray, y_hat1: np.ndarray) -> np.ndarray:
    """(C,) bool: channels whose held-out prediction differs between two models (rows where
    both predictions and the measurement are finite), beyond :data:`CHANGE_TOL` x rms(y_c)."""
    y = np.asarray(y, float).reshape(len(y), -1)
    y0, y1 = (np.asarray(a, float).reshape(y.shape) for a in (y_hat0, y_hat1))
    ok = np.isfinite(y).all(axis=1) & np.isfinite(y0).all(axis=1) & np.isfinite(y1).all(axis=1)
    if not ok.any():
        return np.ones(y.shape[1], bool)
    scale = np.sqrt(np.mean(y[ok] ** 2, axis=0))
    return np.max(np.abs(y1[ok] - y0[ok]), axis=0) > CHANGE_TOL * scale


def practical_gain(y0: np.ndarray, y_hat0: np.ndarray, y1: np.ndarray, y_hat1: np.ndarray
                   ) -> tuple[float, np.ndarray]:
    """Relative drop of the held-out error (:func:`heldout_error`) of a candidate (``y1``,
    ``y_hat1``: its held-out measurements and predictions) against the model without it (``y0``,
    ``y_hat0``), over the channels the candidate changes (:func:`changed_channels`; 0 if none),
    and the (C,) bool mask of those channels."""
    c0, c1 = channel_nrmse(y0, y_hat0), channel_nrmse(y1, y_hat1)
    use = changed_channels(np.where(np.isfinite(y0), y0, y1), y_hat0, y_hat1)
    use &= np.isfinite(c0) & np.isfinite(c1) & (c0 > 0)
    if not use.any():
        return 0.0, use
    return float(1.0 - np.exp(np.mean(np.log(np.maximum(c1[use], 1e-300)) - np.log(c0[use])))), use


def _n_free(ident) -> int:
    return len(ident.params) - len(ident.fixed)


def lr_significance(base, cand, n_candidates: int = 1, alpha: float = 0.01) -> dict:
    """Per-channel Gaussian likelihood-ratio test of a candidate fit against the base fit.

    Args:
        base, cand: :class:`~cablelab.fit.Identification` without / with the effect (full record).
    Returns:
        ``{"p_value", "lr", "n_eff", "delta_bic", "passes"}`` (passes: p < alpha / n_candidates).
    """
    ok = np.isfinite(base.residual).all(axis=1) & np.isfinite(cand.residual).all(axis=1)
    r0, r1 = base.residual[ok], cand.residual[ok]
    n = r1.shape[0]
    rss0 = np.sum(r0**2, axis=0)
    rss1 = np.sum(r1**2, axis=0)
    # a channel whose residual is round-off under both fits (rms < 1e-12 in its unit: a channel
    # the dataset zeroes where it is not excited, e.g. the suspended yaw) carries no information;
    # its log ratio of two round-offs would swamp the test either way
    live = np.sqrt(np.maximum(rss0, rss1) / max(n, 1)) > 1e-12
    if not live.any():
        live[:] = True
    r1, rss0, rss1 = r1[:, live], rss0[live], rss1[live]
    step = int(cand.extra.get("sample_step", 1))  # parallel-filtered data: fs / (2 f_c)
    n_eff = np.array([effective_samples(r1[:, c], step) for c in range(r1.shape[1])])
    with np.errstate(divide="ignore", invalid="ignore"):
        lr = float(np.sum(n_eff * np.log(np.maximum(rss0, 1e-300) / np.maximum(rss1, 1e-300))))
    dp = max(_n_free(cand) - _n_free(base), 1)
    p_value = float(scipy.stats.chi2.sf(lr, dp)) if np.isfinite(lr) else 0.0
    n_mean = float(np.mean(n_eff))
    return {"p_value": p_value, "lr": lr, "n_eff": n_mean, "delta_bic": -lr + dp * np.log(n_mean),
            "passes": bool(p_value < alpha / max(n_candidates, 1))}
