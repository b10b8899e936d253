"""Ambiguity: two candidate effects that explain the same residual, within noise.

A ranking names the candidate with the lowest held-out error first. When a second candidate
removes as much of the error and does it with the same correction, the recording cannot tell them
apart (a spring preload and a stance mass on a hopping leg with one stance depth; a slew offset
and a payload mass when the boom never turns): naming a winner would be a guess. Two candidates
a, b that both help are *ambiguous* when

1. their held-out errors are equal within noise: ``|log e_a - log e_b|`` is at most
   :data:`SPREAD_SIGMAS` x its block-bootstrap standard deviation (paired: the same resampled
   time blocks for both; :func:`paired_log_spread`), or at most :data:`RELATIVE_TOL` of the
   smaller of the two log-reductions ``log(e_0 / e)``, and
2. they act alike: their regressor columns, after projecting out the model's own columns, are
   collinear (first canonical correlation >= :data:`COLLINEAR`; :func:`canonical_correlation`),
   or their held-out corrections ``y_hat_a - y_hat_0`` and ``y_hat_b - y_hat_0`` point the same
   way (cosine >= :data:`SIMILAR`; also for effects without linear columns, e.g. a delay).
"""
from __future__ import annotations

import numpy as np

#: first canonical correlation of two projected column blocks above which they count as collinear
COLLINEAR = 0.9
#: cosine of two held-out corrections above which they count as the same correction
SIMILAR = 0.9
#: bootstrap standard deviations within which two held-out errors are equal
SPREAD_SIGMAS = 2.0
#: share of the smaller log error reduction within which two held-out errors are equal
RELATIVE_TOL = 0.1
#: time blocks and resamples of the paired block bootstrap
BLOCKS, RESAMPLES = 20, 400


def canonical_correlation(a: np.ndarray, b: np.ndarray, tol: float = 1e-9) -> float:
    """Largest canonical correlation (uncentred) of the column spaces of ``a`` (n, p) and ``b``
    (n, q): 1 when a combination of one block's columns is a combination of the other's; 0 when
    a block has no column (or only zero columns)."""
    def basis(x):
        x = np.asarray(x, float).reshape(x.shape[0], -1)
        norms = np.linalg.norm(x, axis=0)
        x = x[:, norms > tol * max(norms.max(initial=0.0), 1e-300)]
        if x.shape[1] == 0:
            return None
        u, s, _ = np.linalg.svd(x / np.linalg.norm(x, axis=0), full_matrices=False)
        return u[:, s > tol * s[0]]

    qa, qb = basis(a), basis(b)
    if qa is None or qb is None:
        return 0.0
    return float(min(1.0, np.linalg.svd(qa.T @ qb, compute_uv=False)[0]))


def project_out(base: np.ndarray, block: np.ndarray) -> np.ndarray:
    """``block`` (n, q) minus its least-squares projection on the columns of ``base`` (n, p)."""
    if base.shape[1] == 0 or block.shape[1] == 0:
        return block
    coef, *_ = np.linalg.lstsq(base, block, rcond=None)
    return block - base @ coef


def _block_sums(y: np.ndarray, y_hat: np.ndarray, blocks: int) -> tuple[np.ndarray, np.ndarray]:
    """Per time block and channel: sum of squared errors and of squared measurements (finite rows)."""
    ok = np.isfinite(y).all(axis=1) & np.isfinite(y_hat).all(axis=1)
    e2 = np.where(ok[:, None], (y - y_hat) ** 2, 0.0)
    y2 = np.where(ok[:, None], y ** 2, 0.0)
    edges = np.linspace(0, y.shape[0], blocks + 1).astype(int)
    return np.add.reduceat(e2, edges[:-1], axis=0), np.add.reduceat(y2, edges[:-1], axis=0)


def paired_log_spread(y_a, y_hat_a, y_b, y_hat_b, *, blocks: int = BLOCKS,
                      resamples: int = RESAMPLES, seed: int = 0) -> tuple[float, float]:
    """``(d, sd)``: d = log e_a - log e_b of the two held-out errors (geometric mean over channels
    of the per-channel NRMSE, as :func:`~cablelab.diagnose.score.heldout_error`) and the
    standard deviation of d under a block bootstrap over time that resamples the same blocks for
    both (the spread of the difference the noise alone leaves)."""
    ya, yha = (np.asarray(v, float).reshape(len(v), -1) for v in (y_a, y_hat_a))
    yb, yhb = (np.asarray(v, float).reshape(len(v), -1) for v in (y_b, y_hat_b))
    blocks = max(2, min(blocks, ya.shape[0] // 10))
    ea, sa = _block_sums(ya, yha, blocks)
    eb, sb = _block_sums(yb, yhb, blocks)
    live = (sa.sum(axis=0) > 0) & (sb.sum(axis=0) > 0)

    def log_err(counts, e, s):
        num, den = counts @ e[:, live], counts @ s[:, live]
        return 0.5 * np.mean(np.log(np.maximum(num, 1e-300) / np.maximum(den, 1e-300)), axis=-1)

    one = np.ones(blocks)
    d = float(log_err(one, ea, sa) - log_err(one, eb, sb))
    rng = np.random.default_rng(seed)
    idx = rng.integers(0, blocks, size=(resamples, blocks))
    counts = np.zeros((resamples, blocks))
    np.add.at(counts, (np.repeat(np.arange(resamples), blocks), idx.ravel()), 1.0)
    ds = log_err(counts, ea, sa) - log_err(counts, eb, sb)
    return d, float(np.std(ds))


def correction_cosine(y_hat0: np.ndarray, y_hat_a: np.ndarray, y_hat_b: np.ndarray,
                      scale: np.ndarray | None = None) -> float:
    """Cosine of the two corrections ``y_hat_a - y_hat0`` and ``y_hat_b - y_hat0`` (rows where all
    are finite; channels weighted by ``scale``, e.g. 1 / rms(y_c)); 0 if either is zero."""
    y0, ya, yb = (np.asarray(v, float).reshape(len(v), -1) for v in (y_hat0, y_hat_a, y_hat_b))
    ok = np.isfinite(y0).all(axis=1) & np.isfinite(ya).all(axis=1) & np.isfinite(yb).all(axis=1)
    w = np.ones(y0.shape[1]) if scale is None else np.asarray(scale, float)
    ca, cb = ((ya[ok] - y0[ok]) * w).ravel(), ((yb[ok] - y0[ok]) * w).ravel()
    na, nb = np.linalg.norm(ca), np.linalg.norm(cb)
    return float(ca @ cb / (na * nb)) if na > 0 and nb > 0 else 0.0


def ambiguous_pair(err0: float, a: dict, b: dict, scale=None) -> dict | None:
    """Whether candidates ``a`` and ``b`` are ambiguous (module doc); each a dict with ``error``
    (held-out), ``y`` and ``y_hat`` (held-out measurements and predictions), ``y_hat0`` (the
    model's held-out prediction) and ``columns`` ((n, q) projected columns, q may be 0).

    Returns:
        ``{"difference", "spread", "collinearity", "cosine"}`` when ambiguous, else None.
    """
    if not (a["error"] < err0 and b["error"] < err0):
        return None
    d, sd = paired_log_spread(a["y"], a["y_hat"], b["y"], b["y_hat"])
    red = min(np.log(err0 / a["error"]), np.log(err0 / b["error"]))
    if abs(d) > max(SPREAD_SIGMAS * sd, RELATIVE_TOL * red):
        return None
    cc = canonical_correlation(a["columns"], b["columns"])
    cos = correction_cosine(a["y_hat0"], a["y_hat"], b["y_hat"], scale)
    if cc < COLLINEAR and cos < SIMILAR:
        return None
    return {"difference": d, "spread": sd, "collinearity": cc, "cosine": cos}


def find_ambiguous(err0: float, cands: dict, eligible, scale=None) -> dict:
    """``{effect: {other: evidence}}`` over every pair of ``eligible`` effect ids (those that
    help: significant or above the minimum gain) in ``cands`` (id -> dict of
    :func:`ambiguous_pair`)."""
    ids = [c for c in eligible if c in cands]
    out: dict = {}
    for i, a in enumerate(ids):
        for b in ids[i + 1:]:
            ev = ambiguous_pair(err0, cands[a], cands[b], scale)
            if ev is not None:
                out.setdefault(a, {})[b] = ev
                out.setdefault(b, {})[a] = ev
    return out


def describe(effect: str, others: list[str]) -> str:
    """The clause of the explanation: the data cannot tell these apart."""
    return (f"; ambiguous with {', '.join(others)}: explains the same residual within noise, this "
            f"recording cannot tell {effect} from {' or '.join(others)}")


__all__ = ["COLLINEAR", "SIMILAR", "ambiguous_pair", "canonical_correlation", "correction_cosine",
           "describe", "find_ambiguous", "paired_log_spread", "project_out"]
