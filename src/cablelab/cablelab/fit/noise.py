"""Noise of channels that mix several sensors: per-sensor noise levels and per-sample whitening.

A plant whose output channels are linear combinations of sensor readings, ``y_n = M_n s_n`` (e.g.
a cable robot's wrench channels ``W(p) d`` from eight dynamometers), gives the fit correlated
channel noise whose covariance changes with the sample: ``C_n = M_n diag(v) M_n^T`` for
independent sensors of variances ``v``. Weighting each channel by one number then mixes a quiet
sensor's information with a noisy one's; generalised least squares whitens each sample with
``C_n^{-1/2}`` instead (Aitken). The variances are not known: :func:`sensor_variances` estimates
them by maximum likelihood from the residual of a first fit (feasible GLS), with Fisher scoring
for the variance components (the residual ``r_n ~ N(0, C_n)``, linear in ``v``), started from the
moment estimate ``E[r r^T] = sum_k v_k m_k m_k^T``.

Time correlation is left to the standard errors (their AR(1) inflation,
:func:`cablelab.fit.identification.effective_samples`): for regressors much slower than the noise's correlation time the noise
spectrum is flat over their band, and ordinary and generalised least squares in time have the
same efficiency (Grenander's condition); prewhitening would change the estimate by noise only.
"""
from __future__ import annotations

import numpy as np

#: Fisher-scoring iterations of :func:`sensor_variances` (relative change below VAR_TOL stops)
VAR_ITERATIONS = 50
VAR_TOL = 1e-6
#: a sensor variance is kept at least this fraction of the largest (every C_n positive definite)
VAR_FLOOR = 1e-6
#: rows of the residual the variances are estimated from (evenly spread over the record; a few
#: thousand determine a handful of variances to a few per cent, enough for weights, and keep
#: the scoring cheap next to the fit itself)
VAR_SAMPLES = 4000
#: the moment estimate that starts the scoring, floored at this fraction of the largest (a
#: negative or zero moment estimate would start it on the boundary)
START_FLOOR = 1e-3


def _rows(residual: np.ndarray, noise_map: np.ndarray):
    r = np.asarray(residual, dtype=float)
    m = np.asarray(noise_map, dtype=float)
    if m.ndim != 3 or m.shape[:2] != r.shape:
        raise ValueError(f"noise map of shape {m.shape} for a residual of shape {r.shape}")
    ok = np.flatnonzero(np.isfinite(r).all(axis=1) & np.isfinite(m.reshape(m.shape[0], -1)).all(axis=1))
    if ok.size > VAR_SAMPLES:
        ok = ok[np.linspace(0, ok.size - 1, VAR_SAMPLES).round().astype(int)]
    return r[ok], m[ok]


def sensor_variances(residual: np.ndarray, noise_map: np.ndarray) -> np.ndarray:
    """(S,) maximum-likelihood noise variances of the S independent sensors behind the channels.

    Args:
        residual: (N, C) residual of a fit (rows with NaN are left out; at most
            :data:`VAR_SAMPLES` rows, evenly spread, are used).
        noise_map: (N, C, S) the channels' map of the sensor readings, ``y_n = M_n s_n``.
    Returns:
        the variances (units of the sensors squared); a sensor the residual cannot see (its
        column of the map zero on every used row) gets the floor :data:`VAR_FLOOR` x the largest.
    """
    r, m = _rows(residual, noise_map)
    s = m.shape[2]
    if r.shape[0] < s + 1:
        return np.ones(s)
    # moment start: E[(m_k . r)^2] = sum_l v_l (m_k . m_l)^2
    mt = np.swapaxes(m, 1, 2)
    g = mt @ m
    h = (mt @ r[..., None])[..., 0] ** 2
    v = np.linalg.lstsq((g ** 2).sum(axis=0), h.sum(axis=0), rcond=None)[0]
    top = max(float(np.max(v)), float(np.mean(r ** 2)), 1e-300)
    v = np.maximum(v, START_FLOOR * top)

    def loglik(v):
        lower = np.linalg.cholesky((m * v) @ mt)
        z = np.linalg.solve(lower, r[..., None])[..., 0]
        return -np.log(np.einsum("ncc->nc", lower)).sum() - 0.5 * float(np.sum(z * z))

    best = loglik(v)
    for _ in range(VAR_ITERATIONS):
        cim = np.linalg.solve((m * v) @ mt, m)                       # C^-1 M   (N, C, S)
        u = (np.swapaxes(cim, 1, 2) @ r[..., None])[..., 0]          # m_k^T C^-1 r
        q = mt @ cim                                                 # m_k^T C^-1 m_l
        score = 0.5 * ((u ** 2).sum(axis=0) - np.einsum("nkk->k", q))
        fisher = 0.5 * (q ** 2).sum(axis=0)
        step = np.linalg.lstsq(fisher, score, rcond=None)[0]
        # scoring in the log variances (every variance stays positive), step halved until the
        # likelihood rises: the plain step can overshoot towards a singular covariance
        dlog = np.clip(step / v, -2.0, 2.0)
        for _ in range(30):
            new = np.maximum(v * np.exp(dlog), VAR_FLOOR * float(np.max(v)))
            cand = loglik(new)
            if cand >= best:
                break
            dlog = 0.5 * dlog
        else:
            break
        change = float(np.max(np.abs(new - v) / v))
        v, best = new, cand
        if change < VAR_TOL:
            break
    return v

def whitening(noise_map: np.ndarray, variances: np.ndarray) -> np.ndarray:
    """(N, C, C) per-sample whitening matrices ``L_n^{-1}`` (``L_n L_n^T = M_n diag(v) M_n^T``,
    lower triangular), scaled so that their determinants' geometric mean is 1 (weighted units
    like :func:`cablelab.fit.identification.noise_weights`). A sample whose covariance is singular
    (a channel no sensor reaches, or a non-finite map) gets its channels' mean whitening."""
    m = np.asarray(noise_map, dtype=float)
    n, c, _ = m.shape
    m = np.nan_to_num(m)
    cov = (m * np.asarray(variances, float)) @ np.swapaxes(m, 1, 2)
    scale = np.trace(cov, axis1=1, axis2=2) / c
    ref = float(np.median(scale[scale > 0])) if np.any(scale > 0) else 1.0
    # a relative floor keeps every covariance positive definite (a channel without noise of its
    # own is then weighed as if it had a round-off level of noise, not an infinite weight)
    cov = cov + (1e-12 * ref) * np.eye(c)[None]
    lower = np.linalg.cholesky(cov)
    w = np.linalg.inv(lower)
    logdet = -np.log(np.einsum("ncc->nc", lower)).sum(axis=1) / c
    return w / np.exp(np.mean(logdet))


def noise_whitening(residual: np.ndarray, noise_map: np.ndarray) -> np.ndarray:
    """:func:`whitening` with the variances :func:`sensor_variances` estimates from ``residual``."""
    return whitening(noise_map, sensor_variances(residual, noise_map))
