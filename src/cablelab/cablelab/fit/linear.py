"""Linear-in-the-parameters least squares with the lessons of 002 sec. 5.2-5.3.

``solve_linear(phi, y, params)`` solves ``y = phi @ theta`` over N samples and C channels with:

* channel weighting (each channel divided by its RMS so torques and forces weigh alike), or a
  per-sample whitening of the channels (generalised least squares, :mod:`.noise`),
* column scaling, SVD rank and condition number on the scaled regressor (for a well-conditioned
  regressor from the small ``p x p`` Gram matrix of the scaled columns, see :func:`_solve_gram`;
  otherwise, and for every rank decision near the threshold, from the SVD of the tall regressor),
* unidentifiable directions named as parameter combinations (null space of the scaled regressor)
  instead of returning nonsense; optionally base parameters by QR with column pivoting
  (002 sec. 5.3: dependent columns regrouped into the independent ones),
* bounded least squares (:func:`scipy.optimize.lsq_linear`) when the unconstrained solution leaves
  the physical bounds of a parameter,
* the LS covariance ``sigma^2 (Phi^T Phi)^-1`` with ``sigma^2 = RSS / (n - p)`` for standard errors.
"""
from __future__ import annotations

from dataclasses import dataclass, field
from typing import Sequence

import numpy as np
import scipy.linalg
import scipy.optimize

from ..errors import CablelabError
from ..effects.base import Param

#: singular values below RANK_TOL * largest (of the column-scaled regressor) count as zero
RANK_TOL = 1e-8
#: columns with a norm below ZERO_COLUMN * the largest column norm count as not excited
ZERO_COLUMN = 1e-7
#: largest condition number (2-norm, column-scaled) solved through the Gram matrix; above it the
#: SVD of the tall regressor decides rank and solution (the Gram matrix squares the condition
#: number: at 1e5 its smallest eigenvalue still carries about 6 correct digits)
GRAM_COND = 1e5


class RankDeficient(CablelabError):
    """A rank-deficient regressor (the one-line message names the unidentifiable directions)."""


@dataclass
class LinearFit:
    """Result of :func:`solve_linear`.

    Attributes:
        names, units: the free parameters (or base-parameter combinations when regrouped).
        theta: (p,) estimates; stderr (p,) standard errors; cov (p, p) covariance.
        rank, cond: rank and condition number (2-norm) of the column-scaled regressor.
        n: equations used (valid samples x channels); rss: weighted residual sum of squares;
        sigma2: residual variance estimate (weighted units).
        unidentifiable: named null-space directions (empty when full rank).
        base: for a regrouped fit, the base-parameter definitions (``"M + 0.5 Fc"``).
        active_bounds: names of parameters held at a bound by bounded LS.
        channel_scale: (C,) weights applied to the channels, or (N, C, C) per-sample whitening
            matrices (:func:`weigh`).
    """

    names: tuple[str, ...]
    units: tuple[str, ...]
    theta: np.ndarray
    stderr: np.ndarray
    cov: np.ndarray
    rank: int
    cond: float
    n: int
    rss: float
    sigma2: float
    unidentifiable: list[str] = field(default_factory=list)
    base: list[str] = field(default_factory=list)
    active_bounds: list[str] = field(default_factory=list)
    channel_scale: np.ndarray | None = None

    @property
    def params(self) -> dict[str, float]:
        """name -> estimate."""
        return {k: float(v) for k, v in zip(self.names, self.theta)}

    def table(self) -> list[dict]:
        """[{name, value, stderr, unit}] for JSON / reports."""
        return [{"name": k, "value": float(v), "stderr": float(s), "unit": u}
                for k, v, s, u in zip(self.names, self.theta, self.stderr, self.units)]


def _combo(names: Sequence[str], vec: np.ndarray, tol: float = 0.05) -> str:
    """A readable linear combination ``"M - 0.5 Fc"`` of the significant entries of ``vec``."""
    vec = np.asarray(vec, dtype=float)
    k = int(np.argmax(np.abs(vec)))
    vec = vec / vec[k]
    terms = []
    for name, c in zip(names, vec):
        if abs(c) < tol:
            continue
        mag = "" if abs(abs(c) - 1) < 1e-3 else f"{abs(c):.3g} "
        sign = "-" if c < 0 else "+"
        terms.append((sign, f"{mag}{name}"))
    text = ""
    for i, (sign, term) in enumerate(terms):
        text += (("- " if sign == "-" else "") if i == 0 else f" {sign} ") + term
    return text


def weigh(w: np.ndarray, x: np.ndarray) -> np.ndarray:
    """``x`` (N, C) or (N, C, p) with channel weights ``w`` applied: (C,) scales each channel,
    (N, C, C) multiplies each sample's channels by its matrix (``w[n] @ x[n]``, a whitening)."""
    w = np.asarray(w, dtype=float)
    if w.ndim == 3:
        return np.einsum("ncd,nd...->nc...", w, x)
    return x * (w[None, :, None] if x.ndim == 3 else w[None, :])


def _as_channels(phi, y):
    """``phi`` as (N, C, p) and ``y`` as (N, C) float arrays (one channel when given 2-D / 1-D)."""
    phi = np.asarray(phi, dtype=float)
    y = np.asarray(y, dtype=float)
    return (phi[:, None, :] if phi.ndim == 2 else phi), (y[:, None] if y.ndim == 1 else y)


def solve_linear(phi: np.ndarray, y: np.ndarray, params: Sequence[Param], *,
                 valid: np.ndarray | None = None, channel_scale: np.ndarray | str | None = "rms",
                 bounded: bool = True, rank_tol: float = RANK_TOL,
                 on_deficient: str = "raise") -> LinearFit:
    """Least squares ``y ~ phi @ theta`` with rank check, bounds and covariance.

    Args:
        phi: (N, C, p) regressor (or (N, p) for one channel).
        y: (N, C) (or (N,)) left-hand side (known contributions already subtracted).
        params: the p :class:`Param` (names, units, bounds).
        valid: (N,) mask of usable samples (non-finite rows are dropped too).
        channel_scale: ``"rms"`` (divide each channel by its RMS), None (no weighting), (C,)
            weights, or (N, C, C) per-sample whitening matrices (generalised least squares with a
            channel covariance that changes with the sample, :mod:`.noise`).
        bounded: enforce the parameters' box bounds with bounded LS.
        rank_tol: relative singular-value threshold for the rank.
        on_deficient: ``"raise"`` -> CablelabError naming the unidentifiable directions;
            ``"base"`` -> regroup into base parameters (QR with column pivoting).
    Raises:
        CablelabError: too few samples, or a rank-deficient regressor with ``on_deficient="raise"``.
    """
    phi, y = _as_channels(phi, y)
    n_s, n_c, p = phi.shape
    names = tuple(pp.name for pp in params)
    units = tuple(pp.unit for pp in params)
    if len(names) != p:
        raise ValueError(f"{len(names)} params for {p} regressor columns")
    mask = np.ones(n_s, dtype=bool) if valid is None else np.asarray(valid, dtype=bool).copy()
    mask &= np.isfinite(y).all(axis=1) & np.isfinite(phi.reshape(n_s, n_c * p)).all(axis=1)
    if isinstance(channel_scale, str):
        if channel_scale != "rms":
            raise ValueError(f"channel_scale {channel_scale!r}")
        rms = np.sqrt(np.mean(y[mask] ** 2, axis=0)) if mask.any() else np.ones(n_c)
        w = 1.0 / np.where(rms > 0, rms, 1.0) if n_c > 1 else np.ones(1)
    elif channel_scale is None:
        w = np.ones(n_c)
    else:
        w = np.asarray(channel_scale, dtype=float)
        w = w.reshape(n_s, n_c, n_c) if w.ndim == 3 else w.reshape(n_c)
    # (no free parameter, e.g. every one fixed: no columns, the residual is y itself)
    wm = w[mask] if w.ndim == 3 else w
    a = weigh(wm, phi[mask]).reshape(int(mask.sum()) * n_c, p)
    b = weigh(wm, y[mask]).reshape(-1)
    n = a.shape[0]
    if n <= p:
        raise CablelabError(f"too few valid samples for the fit: {n} equations for {p} parameters "
                            "(record a longer run or use fewer effects)")
    if p == 0:
        rss = float(b @ b)
        return LinearFit((), (), np.zeros(0), np.zeros(0), np.zeros((0, 0)), 0, 1.0, n, rss,
                         rss / n, channel_scale=w)

    lo = np.array([pp.lower for pp in params])
    hi = np.array([pp.upper for pp in params])
    fast = _solve_gram(a, b, lo, hi, bounded)
    if fast is not None:
        theta, active_mask, rss, cov, cond = fast
        active = [names[i] for i in range(p) if active_mask[i] != 0]
        sigma2 = rss / (n - p)
        cov = sigma2 * cov
        return LinearFit(names, units, theta, np.sqrt(np.clip(np.diag(cov), 0, None)), cov, p,
                         cond, n, rss, sigma2, active_bounds=active, channel_scale=w)

    s = np.linalg.norm(a, axis=0)
    # a column at round-off level next to the others (e.g. an acceleration differentiated from a
    # constant-velocity ramp) carries no information: treat it as zero, not as a scaled-up column
    s = np.where(s > ZERO_COLUMN * s.max(), s, 0.0) if s.size else s
    a = np.where(s > 0, a, 0.0)
    s_safe = np.where(s > 0, s, 1.0)
    a_s = a / s_safe
    u, sv, vt = np.linalg.svd(a_s, full_matrices=False)
    rank = int(np.sum(sv > sv[0] * rank_tol)) if sv[0] > 0 else 0
    cond = float(sv[0] / sv[-1]) if sv[-1] > 0 else float("inf")
    if rank < p:
        dirs = [_combo(names, vt[i] / s_safe) for i in range(rank, p)]
        if on_deficient == "raise":
            raise RankDeficient(
                f"rank-deficient fit (rank {rank} of {p}, condition {cond:.3g}): "
                f"{'; '.join(dirs)} cannot be identified from this data; fix a parameter "
                "(--fix NAME=VALUE), drop an effect (--effects), or record motion that excites it")
        return _solve_base(a, b, s_safe, names, units, rank, cond, dirs, w)

    theta_s = vt.T @ ((u.T @ b) / sv)
    theta = theta_s / s_safe
    active: list[str] = []
    if bounded and (np.any(theta < lo) or np.any(theta > hi)):
        res = scipy.optimize.lsq_linear(a_s, b, bounds=(lo * s_safe, hi * s_safe), method="bvls")
        theta = res.x / s_safe
        active = [names[i] for i in range(p) if res.active_mask[i] != 0]
    r = b - a @ theta
    rss = float(r @ r)
    sigma2 = rss / (n - p)
    cov_s = (vt.T / sv**2) @ vt
    cov = sigma2 * cov_s / np.outer(s_safe, s_safe)
    stderr = np.sqrt(np.clip(np.diag(cov), 0, None))
    return LinearFit(names, units, theta, stderr, cov, rank, cond, n, rss, sigma2,
                     active_bounds=active, channel_scale=w)


def _solve_gram(a: np.ndarray, b: np.ndarray, lo: np.ndarray, hi: np.ndarray, bounded: bool):
    """The least squares of :func:`solve_linear` through the Gram matrix of the column-scaled
    regressor, for a full-rank, well-conditioned ``a`` (N x p, N >> p): one pass ``a^T a`` instead
    of an SVD of the tall matrix (about 15-30x less work for a few parameters).

    Numerical safety: the columns are scaled to unit norm before the eigendecomposition; the
    solution gets one step of iterative refinement from the true residual (corrected
    semi-normal equations, accurate like QR while eps cond^2 << 1); bounded LS runs on the
    equivalent p x p problem ``[R; 0] x ~ [z; rho]`` (``R^T R`` the scaled Gram matrix, ``rho``
    the unconstrained residual norm), whose cost and gradient equal the tall problem's.

    Returns:
        ``(theta, active_mask, rss, cov_unit, cond)`` (``cov_unit = (a^T a)^-1``), or None when a
        column is at round-off level, the condition number exceeds :data:`GRAM_COND` or the
        Gram matrix is not finite: then the SVD path decides (rank, null space, base parameters).
    """
    p = a.shape[1]
    gram = a.T @ a
    s2 = np.diag(gram).copy()
    if not np.all(np.isfinite(gram)) or s2.max() <= 0:
        return None
    s = np.sqrt(s2)
    if np.any(s <= ZERO_COLUMN * s.max()):
        return None
    gram_s = gram / np.outer(s, s)
    lam, vec = np.linalg.eigh(gram_s)
    if not (lam[0] > 0 and lam[-1] > 0 and lam[0] * GRAM_COND ** 2 > lam[-1]):
        return None

    def solve(rhs_s):
        return vec @ ((vec.T @ rhs_s) / lam)

    g_s = (a.T @ b) / s
    theta_s = solve(g_s)
    r = b - a @ (theta_s / s)
    theta_s = theta_s + solve((a.T @ r) / s)     # one refinement step from the true residual
    theta = theta_s / s
    active_mask = np.zeros(p)
    if bounded and (np.any(theta < lo) or np.any(theta > hi)):
        r = b - a @ theta
        rho = float(np.sqrt(r @ r))
        root = np.sqrt(lam)
        r_small = np.vstack([root[:, None] * vec.T, np.zeros((1, p))])
        z_small = np.append((vec.T @ g_s) / root, rho)
        res = scipy.optimize.lsq_linear(r_small, z_small, bounds=(lo * s, hi * s), method="bvls")
        theta = res.x / s
        active_mask = res.active_mask
    r = b - a @ theta
    rss = float(r @ r)
    cov_unit = ((vec / lam) @ vec.T) / np.outer(s, s)
    return theta, active_mask, rss, cov_unit, float(np.sqrt(lam[-1] / lam[0]))


def _solve_base(a, b, s, names, units, rank, cond, dirs, w) -> LinearFit:
    """Base parameters (002 sec. 5.3): keep ``rank`` independent columns (QR, column pivoting),
    regroup the dependent ones: A_dep = A_ind B, base_i = theta_i + sum_j B_ij theta_j."""
    a_s = a / s
    _, r_mat, piv = scipy.linalg.qr(a_s, mode="economic", pivoting=True)
    ind, dep = piv[:rank], piv[rank:]
    b_s = scipy.linalg.solve_triangular(r_mat[:rank, :rank], r_mat[:rank, rank:])
    bmat = b_s / s[ind][:, None] * s[dep][None, :]
    base_names = []
    for i, k in enumerate(ind):
        terms = [names[k]] + [f"{bmat[i, j]:+.3g} {names[d]}" for j, d in enumerate(dep)
                              if abs(bmat[i, j]) > 1e-9]
        base_names.append(" ".join(terms).replace("+-", "-"))
    a_ind = a[:, ind]
    theta, *_ = np.linalg.lstsq(a_ind, b, rcond=None)
    r = b - a_ind @ theta
    rss = float(r @ r)
    sigma2 = rss / (a.shape[0] - rank)
    cov = sigma2 * np.linalg.inv(a_ind.T @ a_ind)
    return LinearFit(tuple(base_names), tuple(units[k] for k in ind), theta,
                     np.sqrt(np.clip(np.diag(cov), 0, None)), cov, rank, cond, a.shape[0], rss,
                     sigma2, unidentifiable=dirs, base=base_names, channel_scale=w)


def unexcited_columns(phi: np.ndarray, y: np.ndarray, params: Sequence[Param], *,
                      valid: np.ndarray | None = None, channel_scale="rms",
                      rank_tol: float = RANK_TOL) -> list[int]:
    """Indices of the columns to hold so that the rest of ``phi`` has full rank: the columns the
    data do not excite at all first (norm below :data:`ZERO_COLUMN` x the largest, as
    :func:`solve_linear`), then, while the column-scaled regressor is rank-deficient, the column
    that carries most of its null space (sum of squared null-vector components); between equal
    shares the later column (the effect added last, not the model's own) is held.

    Args: as :func:`solve_linear` (``y`` only sets the channel weights).
    """
    phi, y = _as_channels(phi, y)
    n_s, n_c, p = phi.shape
    mask = np.ones(n_s, dtype=bool) if valid is None else np.asarray(valid, dtype=bool).copy()
    mask &= np.isfinite(y).all(axis=1) & np.isfinite(phi.reshape(n_s, n_c * p)).all(axis=1)
    if isinstance(channel_scale, str):
        rms = np.sqrt(np.mean(y[mask] ** 2, axis=0)) if mask.any() else np.ones(n_c)
        w = 1.0 / np.where(rms > 0, rms, 1.0) if n_c > 1 else np.ones(1)
    else:
        w = np.ones(n_c) if channel_scale is None else np.asarray(channel_scale, float).reshape(n_c)
    a = (phi[mask] * w[None, :, None]).reshape(int(mask.sum()) * n_c, p)
    if p == 0 or a.shape[0] == 0:
        return []
    s = np.linalg.norm(a, axis=0)
    held = [i for i in range(p) if not s[i] > ZERO_COLUMN * s.max()]
    keep = [i for i in range(p) if i not in held]
    while keep:
        a_s = a[:, keep] / s[keep]
        _, sv, vt = np.linalg.svd(a_s, full_matrices=False)
        rank = int(np.sum(sv > sv[0] * rank_tol))
        if rank == len(keep):
            break
        share = np.sum(vt[rank:] ** 2, axis=0)
        # ties (identical columns) go to the later column: the tolerance keeps round-off out
        top = np.flatnonzero(share >= share.max() * (1 - 1e-6))[-1]
        held.append(keep.pop(int(top)))
    return sorted(held)
