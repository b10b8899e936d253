"""Simulation-based identification (free-run fit) on :func:`mujoco.minimize.least_squares`.

For models that are not linear in their parameters, or when only the motion is measured, the
parameters are found by simulating the plant (MuJoCo, :func:`mujoco.rollout.rollout`) and
matching the simulated outputs to the measured ones within box bounds. Two objectives:

* ``"nmse"`` (003 eq. 28): ``J = sum_c sum_n (y_c - y_sim,c)^2 / sum_n (y_c - mean y_c)^2``; the
  residual vector is ``(y_sim,c - y_c) / ||y_c - mean y_c||``, so ``||r||^2 = J``.
* ``"pearson"`` (000 eq. 3-7): maximise the mean Pearson correlation ``R = mean_c rho_c``. With
  standardised signals z (zero mean, unit variance), ``||z_sim - z||^2 / N = 2 (1 - rho)``, so the
  residual ``(z_sim,c - z_c) / sqrt(2 N C)`` gives ``||r||^2 = 1 - R``: least squares on it
  maximises R (insensitive to gain and offset, like the paper's metric).

Standard errors come from the Gauss-Newton covariance ``s^2 (J^T J)^-1`` at the optimum, with
``s^2 = ||r||^2 / (n - p)``, inflated by ``sqrt((1 + r1) / (1 - r1))`` for the lag-1
autocorrelation r1 of the residual (a free-run residual is smooth, far from white).
"""
from __future__ import annotations

import sys
import time
from dataclasses import dataclass, field
from typing import Callable, Sequence

import numpy as np

from ..errors import CablelabError
from ..effects.base import Param

OBJECTIVES = ("nmse", "pearson")


@dataclass
class SimulationFit:
    """Result of :func:`fit_simulation`.

    Attributes:
        params, stderr: by name; objective: ``"nmse"`` or ``"pearson"``;
        nmse: J of 003 eq. 28 at the optimum; pearson: mean correlation R of 000 eq. 7;
        y_sim: (N, C) simulated output; iterations: optimiser iterations; evaluations: rollouts.
    """

    params: dict
    stderr: dict
    objective: str
    nmse: float
    pearson: float
    y_sim: np.ndarray
    iterations: int = 0
    evaluations: int = 0
    extra: dict = field(default_factory=dict)


def _standardise(y: np.ndarray) -> np.ndarray:
    sd = y.std(axis=0)
    return (y - y.mean(axis=0)) / np.where(sd > 0, sd, 1.0)


def objective_residual(y_meas: np.ndarray, y_sim: np.ndarray, objective: str) -> np.ndarray:
    """Residual vector whose squared norm is the NMSE J (003 eq. 28) or 1 - R (000 eq. 7)."""
    y_meas = np.asarray(y_meas, float).reshape(y_meas.shape[0], -1)
    y_sim = np.asarray(y_sim, float).reshape(y_meas.shape)
    if objective == "nmse":
        spread = np.linalg.norm(y_meas - y_meas.mean(axis=0), axis=0)
        return ((y_sim - y_meas) / np.where(spread > 0, spread, 1.0)).reshape(-1)
    if objective == "pearson":
        n, c = y_meas.shape
        return ((_standardise(y_sim) - _standardise(y_meas)) / np.sqrt(2.0 * n * c)).reshape(-1)
    raise CablelabError(f"unknown objective {objective!r} (use one of {', '.join(OBJECTIVES)})")


def fit_simulation(simulate: Callable[[list[dict]], np.ndarray], params: Sequence[Param],
                   y_meas: np.ndarray, *, objective: str = "nmse", x0: Sequence[float] | None = None,
                   max_iter: int = 50, verbose: bool = False, progress: bool = False,
                   covariance: bool = True) -> SimulationFit:
    """Bounded fit of simulated to measured outputs.

    Args:
        simulate: ``fn([values, ...]) -> (k, N, C)`` simulated outputs for k parameter sets
            (batch: the finite-difference Jacobian evaluates p sets at once; use
            :func:`mujoco.rollout.rollout` with a list of models).
        params: free parameters with bounds (finite bounds required) and nominal start.
        y_meas: (N, C) measured outputs (same sampling as the simulation).
        objective: ``"nmse"`` (003 eq. 28) or ``"pearson"`` (000 eq. 3-7).
        x0: start (default the nominal values).
        progress: print a line with the objective and an ETA (upper bound: max_iter) on stderr
            every 2 s.
        covariance: compute the standard errors (one batch of 2p extra rollouts); False: NaN
            (e.g. the fits of cross-validation folds, whose spread is the uncertainty).
    Raises:
        CablelabError: unknown objective, infinite bounds, start outside the bounds.
    """
    import mujoco.minimize as mjmin

    if objective not in OBJECTIVES:
        raise CablelabError(f"unknown objective {objective!r} (use one of {', '.join(OBJECTIVES)})")
    names = [p.name for p in params]
    lo = np.array([p.lower for p in params], float)
    hi = np.array([p.upper for p in params], float)
    if not (np.all(np.isfinite(lo)) and np.all(np.isfinite(hi))):
        raise CablelabError("simulation-based fit needs finite bounds for every parameter")
    start = np.array(x0 if x0 is not None else [p.nominal for p in params], float)
    if np.any(start < lo) or np.any(start > hi):
        raise CablelabError(f"start {dict(zip(names, start))} outside the bounds")
    y_meas = np.asarray(y_meas, float).reshape(len(y_meas), -1)
    count = {"n": 0}

    def residual(xs):
        xs = np.asarray(xs, float).reshape(len(names), -1)
        sims = np.asarray(simulate([dict(zip(names, xs[:, k])) for k in range(xs.shape[1])]))
        count["n"] += xs.shape[1]
        return np.stack([objective_residual(y_meas, s, objective) for s in sims], axis=1)

    scale = np.maximum(np.abs(start), 1e-3 * (hi - lo))
    t0 = time.monotonic()
    last = [t0]

    def report(trace):
        now = time.monotonic()
        if progress and now - last[0] >= 2.0 and trace:
            last[0] = now
            it = len(trace)
            eta = (now - t0) / it * max(max_iter - it, 0)
            print(f"[fit {objective}] iteration {it}/{max_iter}, objective {2 * trace[-1].objective:.4g}, "
                  f"{count['n']} rollouts, ETA <= {eta:.0f} s", file=sys.stderr, flush=True)

    x, trace = mjmin.least_squares(start, residual, bounds=[lo, hi], x_scale=scale,
                                   max_iter=max_iter, verbose=2 if verbose else 0, xtol=1e-6,
                                   iter_callback=report)
    x = np.clip(np.asarray(x, float).reshape(-1), lo, hi)
    values = dict(zip(names, map(float, x)))
    if not covariance:
        y_sim = np.asarray(simulate([values]))[0].reshape(y_meas.shape)
        nm = float(np.sum(objective_residual(y_meas, y_sim, "nmse") ** 2))
        rho = 1.0 - float(np.sum(objective_residual(y_meas, y_sim, "pearson") ** 2))
        return SimulationFit(values, dict.fromkeys(names, float("nan")), objective, nm, rho, y_sim,
                             iterations=len(trace), evaluations=count["n"])
    # Gauss-Newton covariance from a central finite-difference Jacobian (one batch of 2p rollouts)
    h = 1e-4 * scale
    pts = np.concatenate([np.clip(x[:, None] + np.diag(h), lo[:, None], hi[:, None]),
                          np.clip(x[:, None] - np.diag(h), lo[:, None], hi[:, None]),
                          x[:, None]], axis=1)
    r_all = residual(pts)
    p = len(names)
    dx = np.diag(pts[:, :p] - pts[:, p:2 * p])
    jac = (r_all[:, :p] - r_all[:, p:2 * p]) / np.where(dx != 0, dx, 1.0)
    r0 = r_all[:, -1]
    dof = max(r0.size - p, 1)
    s2 = float(r0 @ r0) / dof
    try:
        cov = s2 * np.linalg.pinv(jac.T @ jac)
        se = np.sqrt(np.clip(np.diag(cov), 0, None))
    except np.linalg.LinAlgError:
        se = np.full(p, np.nan)
    # coloured residuals: inflate by the AR(1) effective sample size, as cablelab.fit.identification
    from .identification import lag1_autocorrelation

    r1 = lag1_autocorrelation(r0.reshape(y_meas.shape))
    inflation = float(np.sqrt((1.0 + r1) / (1.0 - r1)))
    se = se * inflation
    y_sim = np.asarray(simulate([values]))[0].reshape(y_meas.shape)
    nm = float(np.sum(objective_residual(y_meas, y_sim, "nmse") ** 2))
    rho = 1.0 - float(np.sum(objective_residual(y_meas, y_sim, "pearson") ** 2))
    # (what an identifiability analysis needs: the Jacobian at the optimum, its residual and the
    # coloured-residual inflation of the standard errors)
    return SimulationFit(values, dict(zip(names, map(float, se))), objective, nm, rho, y_sim,
                         iterations=len(trace), evaluations=count["n"],
                         extra={"jacobian": jac, "residual": r0, "se_inflation": inflation})


# ----------------------------------------------------------------------------- free-run windows
# A free run of a marginally stable plant is cut into windows of a fixed horizon, each started
# from the measured state (002 sec. 6.1); what the model must reproduce is the deviation of the
# measured motion from each window's start.

def window_length(dt: float, horizon_s: float) -> int:
    """Samples per free-run window of ``horizon_s`` (s) at sample period ``dt`` (s), at least 2."""
    return max(2, int(round(horizon_s / dt)))


def free_run_windows(ds, horizon_s: float) -> tuple[int, int]:
    """``(w, n_win)``: samples per window and number of whole windows of ``horizon_s`` in ``ds``.

    Raises:
        CablelabError: the record is shorter than one window.
    """
    w = window_length(ds.dt, horizon_s)
    n_win = ds.n // w
    if n_win < 1:
        raise CablelabError(f"{ds.source}: record shorter than one free-run window ({horizon_s} s)")
    return w, n_win


def window_starts(x: np.ndarray, w: int) -> np.ndarray:
    """(N, ...) value of ``x`` at the start of the window of ``w`` samples each sample is in."""
    idx = np.arange(len(x))
    return x[(idx // w) * w]


def fit_free_run_windows(run: Callable[[list[dict]], np.ndarray], q: np.ndarray, start: dict,
                         params: Sequence[Param], horizon_s: float, dt: float, *,
                         objective: str = "nmse", max_iter: int = 50,
                         progress: bool = False) -> SimulationFit:
    """:func:`fit_simulation` of a windowed free run to the measured motion.

    Args:
        run: ``fn([values, ...]) -> (k, N, C)`` simulated coordinates, window by window, for k
            complete parameter sets (``start`` updated with the free values).
        q: (N,) or (N, C) measured coordinates (rad or m); the fit matches the deviation of the
            simulated and measured q from each window's start over the whole windows.
        start: values of every parameter (the held ones stay there); params: the free ones.
        horizon_s, dt: window length and sample period, s.
    """
    q = np.asarray(q, float)
    q = q[:, None] if q.ndim == 1 else q
    w = window_length(dt, horizon_s)
    n = (len(q) // w) * w
    base = window_starts(q[:n], w)

    def simulate(sets):
        return run([{**start, **s} for s in sets])[:, :n, :] - base[None]

    return fit_simulation(simulate, params, q[:n] - base, objective=objective, max_iter=max_iter,
                          progress=progress)
