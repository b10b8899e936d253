"""Identify a model's free parameters from a dataset (inverse model, separable least squares).

The free linear parameters come from :func:`~cablelab.fit.linear.solve_linear`. Nonlinear
parameters (a time delay, an unknown pulley radius, ...) are searched outside it (variable
projection / separable least squares): a coarse grid over the box bounds picks the start, then
:func:`mujoco.minimize.least_squares` refines the bounded outer problem whose residual is the
inner linear LS residual. The joint covariance comes from the Jacobian ``[Phi, dr/dtheta_nl]`` at
the optimum, so every parameter has a standard error.
"""
from __future__ import annotations

import itertools
from dataclasses import dataclass, field
from typing import Mapping

import numpy as np
import scipy.linalg

from ..errors import CablelabError
from ..dataset import Dataset
from ..model import Evaluation, Model
from .linear import LinearFit, RankDeficient, solve_linear, unexcited_columns, weigh
from .noise import noise_whitening

#: grid points per nonlinear parameter for the start of the outer search
OUTER_GRID = 11
#: the outer search stops when this many residual evaluations in a row found no lower cost than
#: the best so far and returns the best point: at a kink of the cost (a delay at a whole number
#: of samples, where linear interpolation switches neighbours) the finite-difference step never
#: reduces it and the optimiser would otherwise raise its damping through its whole range, one
#: evaluation per step (about 140 evaluations that all return the start)
OUTER_STALL = 24
#: refits of a model whose effects have higher-order output terms (:func:`identify`): at most
#: this many, until no parameter moves by more than HIGHER_ORDER_TOL of its standard error
HIGHER_ORDER_STEPS = 8
HIGHER_ORDER_TOL = 1e-3


@dataclass
class Identification:
    """Identified model.

    Attributes:
        model: the model.
        params: every parameter by name (free linear, nonlinear, fixed).
        stderr: standard error by name (0 for fixed): the LS covariance, inflated by
            sqrt(tau) for the residual's integrated autocorrelation time tau
            (:func:`correlation_time`; AR(1): (1 + r1) / (1 - r1)); ``extra["stderr_white"]``
            has the uninflated ones.
        units: unit by name.
        fixed: names of the known (not fitted) parameters.
        linear: the inner :class:`LinearFit` (rank, condition, unidentifiable directions).
        y_hat, residual: (N, C) model output and measured - model on the dataset (NaN where not
            valid); valid: (N,) mask.
        channels: channel names.
    """

    model: Model
    params: dict
    stderr: dict
    units: dict
    fixed: tuple
    linear: LinearFit
    y_hat: np.ndarray
    residual: np.ndarray
    valid: np.ndarray
    channels: tuple = ()
    extra: dict = field(default_factory=dict)

    def table(self) -> list[dict]:
        """[{name, value, stderr, unit, fixed}] in model order (``held`` added, True, for a
        parameter the data did not excite, held at its description or neutral value)."""
        held = self.extra.get("held") or {}
        return [{"name": k, "value": float(v), "stderr": float(self.stderr.get(k, 0.0)),
                 "unit": self.units.get(k, ""), "fixed": k in self.fixed,
                 **({"held": True} if k in held else {})}
                for k, v in self.params.items()]

    @property
    def held(self) -> dict:
        """name -> value of the parameters held because the data did not excite them."""
        return dict(self.extra.get("held") or {})

    def held_warning(self) -> str | None:
        """One warning line naming the held parameters (None when nothing is held)."""
        return held_warning(self.held, self.units)

    def physical(self, effect_id: str, ds: Dataset) -> dict:
        """The effect's parameters in the user's terms: ``{name: {"value", "stderr", "unit"}}``
        (:attr:`~cablelab.effects.base.Effect.physical`, else its own parameters), standard errors
        propagated from the fit's covariance by the delta method (the mapping's Jacobian by
        central differences over the free parameters)."""
        from ..effects import get_effect

        eff = get_effect(effect_id)
        if eff.physical is None:
            names = [p.name for p in eff.columns(ds)] + [p.name for p in eff.nonlinear]
            return {k: {"value": float(self.params[k]), "stderr": float(self.stderr.get(k, 0.0)),
                        "unit": self.units.get(k, "")} for k in names if k in self.params}
        out = {}
        for ph in eff.physical(ds):
            try:
                with np.errstate(divide="ignore", invalid="ignore"):
                    value, se = propagate(ph.value, self.params, *self.extra.get("cov", ((), None)),
                                          stderr=self.stderr)
            except KeyError:      # needs a parameter of an effect the model does not have
                continue
            except ZeroDivisionError:
                value, se = float("nan"), float("nan")
            out[ph.name] = {"value": value, "stderr": se, "unit": ph.unit}
        return out

    def reported(self, ds: Dataset) -> tuple[dict, dict]:
        """``(params, internal)``: every parameter of the model in the user's terms (the
        effects' :meth:`physical` parameters where they have them, with ``fixed``/``held``
        flags for the others) and the internal coefficients those replace."""
        table = {r["name"]: {k: v for k, v in r.items() if k != "name"} for r in self.table()}
        params, internal = {}, {}
        for eid in self.model.effects:
            inner = self.internal(eid, ds)
            if not inner:
                continue
            for k in inner:
                internal[k] = table.pop(k, inner[k])
            for k, v in self.physical(eid, ds).items():
                params[k] = {**v, "fixed": False}
        # model order: the effects' own parameters first as they come, physical ones in place
        return {**table, **params}, internal

    def internal(self, effect_id: str, ds: Dataset) -> dict:
        """The effect's fitted coefficients as the regression sees them, when they differ from
        its physical parameters (:meth:`physical`); else empty."""
        from ..effects import get_effect

        eff = get_effect(effect_id)
        if eff.physical is None:
            return {}
        names = [p.name for p in eff.columns(ds)] + [p.name for p in eff.nonlinear]
        return {k: {"value": float(self.params[k]), "stderr": float(self.stderr.get(k, 0.0)),
                    "unit": self.units.get(k, "")} for k in names if k in self.params}

    def effect_params(self, effect_id: str, ds: Dataset) -> dict:
        """The parameters belonging to one effect, by name."""
        from ..effects import get_effect

        eff = get_effect(effect_id)
        names = [p.name for p in eff.columns(ds)] + [p.name for p in eff.nonlinear]
        own = {k: self.params[k] for k in names if k in self.params}
        if eff.derived is not None:
            own.update(eff.derived(eff, own, self.params, ds))
        return own


def propagate(fn, params: Mapping[str, float], names=(), cov=None, *, stderr=None
              ) -> tuple[float, float]:
    """``(fn(params), its standard error)`` by the delta method: ``sqrt(J C J^T)`` with C the
    covariance of the free parameters ``names`` and J the gradient of ``fn`` by central
    differences (step 1e-4 standard errors). Parameters outside ``names`` (fixed) count as exact.
    Without a covariance, the diagonal of ``stderr`` is used (correlations ignored)."""
    p = {k: float(v) for k, v in params.items()}
    value = float(fn(p))
    names = list(names)
    if cov is None or not names:
        names = [k for k in p if stderr and stderr.get(k, 0.0) > 0]
        cov = np.diag([float(stderr[k]) ** 2 for k in names]) if names else np.zeros((0, 0))
    cov = np.asarray(cov, dtype=float)
    sd = np.sqrt(np.clip(np.diag(cov), 0, None))
    grad = np.zeros(len(names))
    for i, k in enumerate(names):
        if k not in p or sd[i] == 0:
            continue
        h = 1e-4 * sd[i]
        hi, lo = dict(p), dict(p)
        hi[k], lo[k] = p[k] + h, p[k] - h
        grad[i] = (float(fn(hi)) - float(fn(lo))) / (2 * h)
    var = float(grad @ cov @ grad) if names else 0.0
    return value, float(np.sqrt(max(var, 0.0)))


def _solve(ev: Evaluation, valid: np.ndarray, on_deficient: str, channel_scale="rms") -> LinearFit:
    """The inner linear least squares on an evaluated model."""
    return solve_linear(ev.phi, ev.lhs, ev.columns, valid=valid, on_deficient=on_deficient,
                        channel_scale=channel_scale)


def _weighted_residual(fit: LinearFit, phi, lhs, valid) -> np.ndarray:
    """Channel-weighted residual (valid rows, others 0) of a full-rank linear fit, flattened."""
    r = weigh(fit.channel_scale, lhs - phi @ fit.theta)
    return np.where(valid[:, None], r, 0.0).reshape(-1)


def identify(model: Model, ds: Dataset, *, on_deficient: str | None = None,
             outer_grid: int = OUTER_GRID, start: Mapping[str, float] | None = None,
             channel_scale=None) -> Identification:
    """Fit the model's free parameters to the dataset.

    Args:
        model: plant + effects + fixed parameters.
        ds: conditioned dataset of the same plant.
        on_deficient: what to do with a rank-deficient regressor: ``"raise"``, ``"base"``
            (regroup to base parameters) or ``"hold"`` (hold the parameters the data do not
            excite at their description or neutral values, :func:`hold_unexcited`; they are
            listed in ``extra["held"]`` and ``fixed``); default: the model's ``unexcited``.
        outer_grid: grid points per nonlinear parameter for the outer search start.
        start: start values of the nonlinear parameters (e.g. the full-record fit when fitting
            cross-validation folds); skips the grid.
        channel_scale: channel weights; default (None): with several channels, noise weights
            1 / sigma_c from the residual of a first RMS-weighted fit (:func:`noise_weights`,
            feasible generalised least squares), so a channel that carries an effect is not
            drowned by channels that do not care; when the dataset has a ``noise_map`` (channels
            that mix independent sensors), per-sample whitening with the sensors' variances
            estimated from that residual instead (:func:`cablelab.fit.noise.noise_whitening`);
            one channel: unweighted.
    Raises:
        CablelabError: too few samples, rank-deficient regressor (names the directions).
    """
    policy = on_deficient or model.unexcited

    def fit(m, start, channel_scale):
        if policy == "hold":
            return _identify_holding(m, ds, outer_grid=outer_grid, start=start,
                                     channel_scale=channel_scale)
        return _identify_once(m, ds, on_deficient=policy, outer_grid=outer_grid, start=start,
                              channel_scale=channel_scale)

    r = fit(model, start, channel_scale)
    if not model.higher_order or r.linear.base:
        return r
    # effects with output terms beyond their columns (Effect.higher_order): those terms at the
    # current estimate join the known part and the fit is repeated until the estimate settles
    # (a fixed point: the terms are small next to the columns', so each step shrinks the change
    # by about their relative size), with the first fit's channel weights
    nl = [p.name for p in model.nonlinear_params()]
    for step in range(1, HIGHER_ORDER_STEPS + 1):
        prev = r
        r = fit(model.evaluated_at(prev.params), {k: prev.params[k] for k in nl} or start,
                prev.linear.channel_scale if channel_scale is None else channel_scale)
        r.model = model
        r.extra["higher_order_steps"] = step
        change = max((abs(r.params[k] - prev.params[k]) / r.stderr[k]
                      for k in r.params if r.stderr.get(k, 0.0) > 0), default=0.0)
        if change < HIGHER_ORDER_TOL:
            break
    return r


def held_value(model: Model, ds: Dataset, name: str) -> float:
    """The value a parameter the data do not excite is held at: the description's
    (``Effect.described``), else the parameter's nominal (the effect's neutral value)."""
    for e in model.effect_objects:
        for p in e.columns(ds):
            if p.name == name:
                if e.described is not None:
                    val = e.described(ds).get(name)
                    if val is not None:
                        return float(val)
                return float(p.nominal)
    raise KeyError(name)


def hold_unexcited(model: Model, ds: Dataset, nl: Mapping[str, float] | None = None) -> dict:
    """``{name: value}`` of the free linear parameters to hold so the rest of the model has a
    full-rank regressor on ``ds`` (:func:`~cablelab.fit.linear.unexcited_columns`, evaluated
    with the nonlinear parameters at ``nl`` or nominal), each at :func:`held_value`."""
    ev = model.evaluate(ds, dict(nl or {}))
    idx = unexcited_columns(ev.phi, ev.lhs, ev.columns, valid=ev.ds.valid)
    return {ev.columns[i].name: held_value(model, ds, ev.columns[i].name) for i in idx}


def _identify_holding(model: Model, ds: Dataset, **kw) -> Identification:
    held: dict[str, float] = {}
    current = model
    for _ in range(len(model.effects) * 64 + 1):
        try:
            r = _identify_once(current, ds, on_deficient="raise", **kw)
        except RankDeficient:
            more = hold_unexcited(current, ds, kw.get("start"))
            if not more:
                raise
            held.update(more)
            current = model.with_effects(model.effects, {**model.fixed, **held})
            continue
        r.model = model
        r.extra["held"] = dict(held)
        return r
    raise RankDeficient(f"rank-deficient fit: holding the unexcited parameters "
                        f"{', '.join(held)} did not leave a full-rank model")


def held_warning(held: Mapping[str, float], units: Mapping[str, str] | None = None) -> str | None:
    """One warning line naming the held parameters and their values, or None."""
    if not held:
        return None
    units = units or {}
    vals = ", ".join(f"{k} = {v:.6g}{(' ' + units[k]) if units.get(k) else ''}"
                     for k, v in held.items())
    return (f"not excited by this recording (rank-deficient fit), held at their description or "
            f"neutral values: {vals}; record motion that excites them, or --strict to refuse")


class _Stalled(Exception):
    """The outer search found no lower cost in :data:`OUTER_STALL` evaluations in a row."""


def _outer_search(model: Model, ds: Dataset, nl_params: list, valid: np.ndarray, channel_scale,
                  outer_grid: int, start: Mapping[str, float] | None):
    """The outer problem of the separable least squares: the nonlinear parameter values that
    minimise the inner linear LS residual (from ``start``, the nominal values or the best grid
    point, refined by :func:`mujoco.minimize.least_squares` inside the box), the model evaluated
    there with its inner fit (rank deficiency raises), and the Jacobian of the weighted residual
    w.r.t. the nonlinear parameters at that fit's theta (for the joint covariance).

    Returns:
        ``(nl_values, evaluation, fit, jac_nl)``.
    """
    names = [p.name for p in nl_params]
    lo = np.array([p.lower for p in nl_params])
    hi = np.array([p.upper for p in nl_params])
    outer = _OuterProblem(model, ds, valid, names, channel_scale)
    costs: dict[bytes, float] = {}      # cost by point: the checks below re-read evaluated ones

    def cost(x):
        key = np.asarray(x, dtype=float).tobytes()
        if key not in costs:
            r = outer.residual(x)
            costs[key] = float(r @ r)
        return costs[key]

    grid = [np.linspace(a, b, outer_grid) for a, b in zip(lo, hi)]
    if start is not None and all(k in start for k in names):
        x0 = np.clip(np.array([float(start[k]) for k in names]), lo, hi)
    elif len(nl_params) > 2:  # keep the grid small: nominal start
        x0 = np.array([p.nominal for p in nl_params])
    else:
        pts = np.array(list(itertools.product(*grid)))
        x0 = pts[int(np.argmin([cost(x) for x in pts]))]

    best = {"cost": np.inf, "x": x0, "stale": 0}

    def one(x):
        r = outer.residual(x)
        c = costs[np.asarray(x, dtype=float).tobytes()] = float(r @ r)
        if c < best["cost"]:
            best.update(cost=c, x=np.array(x, dtype=float), stale=0)
        else:
            best["stale"] += 1
        return r

    def residual(xs):
        xs = np.asarray(xs).reshape(len(names), -1)
        cols = []
        for k in range(xs.shape[1]):
            cols.append(one(xs[:, k]))
            if best["stale"] >= OUTER_STALL:
                raise _Stalled
        return np.stack(cols, axis=1)

    import mujoco.minimize as mjmin

    grid_step = np.array([(b - a) / (outer_grid - 1) for a, b in zip(lo, hi)])
    try:
        x_best, _ = mjmin.least_squares(x0, residual, bounds=[lo, hi], verbose=0,
                                        x_scale=grid_step, max_iter=20, xtol=1e-4)
    except _Stalled:
        x_best = best["x"]
    x_best = np.clip(np.asarray(x_best).reshape(-1), lo, hi)
    if cost(x_best) > cost(x0):
        x_best = x0
    nl_values = dict(zip(names, map(float, x_best)))
    ev = model.evaluate(ds, nl_values)
    fit = _solve(ev, valid, "raise", channel_scale)
    # Jacobian of the residual w.r.t. the nonlinear parameters (theta held) for the covariance
    cols_j = []
    for i, p in enumerate(nl_params):
        h = 0.1 * grid_step[i]
        xp, xm = dict(nl_values), dict(nl_values)
        xp[p.name] = min(nl_values[p.name] + h, hi[i])
        xm[p.name] = max(nl_values[p.name] - h, lo[i])
        rp = _fixed_theta_residual(model, ds, xp, fit, valid)
        rm = _fixed_theta_residual(model, ds, xm, fit, valid)
        cols_j.append((rp - rm) / (xp[p.name] - xm[p.name]))
    return nl_values, ev, fit, np.stack(cols_j, axis=1)


def _identify_once(model: Model, ds: Dataset, *, on_deficient: str = "raise",
                   outer_grid: int = OUTER_GRID, start: Mapping[str, float] | None = None,
                   channel_scale=None) -> Identification:
    if ds.plant != model.plant:
        raise CablelabError(f"dataset of plant {ds.plant} given to a {model.plant} model")
    if channel_scale is None:
        channel_scale = "rms"
        if ds.n_channels > 1:
            first = _identify_once(model, ds, on_deficient=on_deficient, outer_grid=outer_grid,
                                   start=start, channel_scale="rms")
            channel_scale = noise_weights(first.residual) if ds.noise_map is None \
                else noise_whitening(first.residual, ds.noise_map)
            start = {p.name: first.params[p.name] for p in model.nonlinear_params()} or start
    nl_params = model.nonlinear_params()
    nl_values: dict[str, float] = {}
    valid = ds.valid.copy()
    jac_nl = None
    ev = fit = None
    if nl_params:
        # samples valid at every corner of the box: the residual keeps a fixed length
        for corner in itertools.product(*[(p.lower, p.nominal, p.upper) for p in nl_params]):
            valid &= model.apply_nonlinear(ds, dict(zip([p.name for p in nl_params], corner))).valid
        nl_values, ev, f0, jac_nl = _outer_search(model, ds, nl_params, valid, channel_scale,
                                                  outer_grid, start)
        if on_deficient == "raise":
            fit = f0
    if ev is None:
        ev = model.evaluate(ds, nl_values)
    if fit is None:
        fit = _solve(ev, valid, on_deficient, channel_scale)
    phi, cols = ev.phi, ev.columns
    params: dict[str, float] = {}
    stderr: dict[str, float] = {}
    units: dict[str, str] = {}
    if fit.base:
        for k, v, s, u in zip(fit.names, fit.theta, fit.stderr, fit.units):
            params[k], stderr[k], units[k] = float(v), float(s), u
    else:
        for c, v, s in zip(cols, fit.theta, fit.stderr):
            params[c.name], stderr[c.name], units[c.name] = float(v), float(s), c.unit
    for p in nl_params:
        params[p.name], stderr[p.name], units[p.name] = nl_values[p.name], 0.0, p.unit
    cov_names = [] if fit.base else [c.name for c in cols]
    cov_all = np.zeros((0, 0)) if fit.base else np.asarray(fit.cov, dtype=float)
    if jac_nl is not None and not fit.base:
        w = fit.channel_scale
        a = np.where(valid[:, None, None], weigh(w, phi), 0.0).reshape(
            phi.shape[0] * phi.shape[1], phi.shape[2])
        jac = np.concatenate([-a, jac_nl], axis=1)
        jtj = jac.T @ jac
        try:
            cov = fit.sigma2 * np.linalg.pinv(jtj)
            se = np.sqrt(np.clip(np.diag(cov), 0, None))
            cov_names = [c.name for c in cols] + [p.name for p in nl_params]
            cov_all = cov
            for name, s in zip([c.name for c in cols] + [p.name for p in nl_params], se):
                stderr[name] = float(s)
        except np.linalg.LinAlgError:
            pass
    # known parameters
    param_units = {p.name: p.unit for e in model.effect_objects
                   for p in list(e.columns(ds)) + list(e.nonlinear)}
    for k, v in model.fixed.items():
        params[k], stderr[k], units[k] = float(v), 0.0, param_units.get(k, "")
    if fit.base:  # regrouped: predict with the independent columns only
        y_hat = np.full_like(ds.y, np.nan)
    else:
        y_hat = ev.output(fit.theta)
    resid = np.where(valid[:, None], ev.ds.y - y_hat, np.nan)
    # coloured residuals: the LS covariance assumes independent samples; inflate the standard
    # errors by sqrt(n / n_eff) with the AR(1) effective sample size n_eff of the residual taken
    # every `step` samples (parallel-filtered data: one sample per 1 / (2 f_c), else every one)
    step = sample_step(ds)
    r1 = lag1_autocorrelation(resid, step)
    inflation = float(np.sqrt(resid.shape[0] / effective_samples(resid, step, lag1=r1)))
    white = dict(stderr)
    stderr = {k: v * inflation for k, v in stderr.items()}
    return Identification(model, params, stderr, units, tuple(model.fixed), fit, y_hat, resid,
                          valid, tuple(ds.channels),
                          extra={"stderr_white": white, "lag1": r1, "stderr_inflation": inflation,
                                 "sample_step": step,
                                 "cov": (tuple(cov_names), cov_all * inflation ** 2)})


#: a channel residual below this fraction of the largest one is round-off (a channel the plant
#: sets aside, fitted exactly), not a noise level
ROUND_OFF = 1e-9


def noise_weights(residual: np.ndarray) -> np.ndarray:
    """(C,) channel weights 1 / sigma_c, sigma_c = robust (MAD) standard deviation of each
    channel's residual (NaN rows dropped), normalised to a geometric mean of 1; a channel without
    any residual gets the geometric-mean sigma of the others (neutral weight)."""
    r = np.asarray(residual, dtype=float)
    r = r[np.isfinite(r).all(axis=1)]
    if r.shape[0] < 3:
        return np.ones(r.shape[1])
    sig = 1.4826 * np.median(np.abs(r - np.median(r, axis=0)), axis=0)
    sig = np.where(sig > 0, sig, r.std(axis=0))
    sig = np.where(sig > ROUND_OFF * sig.max(), sig, 0.0)    # round-off residual: none at all
    pos = sig[sig > 0]
    if pos.size == 0:
        return np.ones(r.shape[1])
    # a channel fitted exactly (no residual at all, e.g. one a plant sets aside as not excited)
    # carries no noise estimate: it keeps a neutral weight instead of an infinite one
    sig = np.where(sig > 0, sig, np.exp(np.mean(np.log(pos))))
    w = 1.0 / sig
    return w / np.exp(np.mean(np.log(w)))


def lag1_autocorrelation(residual: np.ndarray, step: int = 1) -> float:
    """Lag-1 autocorrelation of a residual (N,) or (N, C) (channels pooled, NaN rows dropped),
    clipped to [0, 0.999]; with ``step`` > 1, between samples ``step`` apart."""
    r = np.asarray(residual, dtype=float)
    r = r.reshape(r.shape[0], -1)
    r = r[np.isfinite(r).all(axis=1)]
    k = max(1, int(step))
    if r.shape[0] < 2 * k + 1:
        return 0.0
    r = r - r.mean(axis=0)
    den = float(np.sum(r * r))
    return float(np.clip(np.sum(r[k:] * r[:-k]) / den, 0.0, 0.999)) if den > 0 else 0.0


def sample_step(ds: Dataset) -> int:
    """Samples per independent sample of a residual of the dataset: ``fs / (2 f_c)`` for a
    parallel-filtered dataset (a signal band-limited to f_c carries 2 f_c independent samples per
    second, Nyquist), else 1."""
    return max(1, int(ds.fs / (2.0 * float(ds.parallel_hz)))) if ds.parallel_hz else 1


def effective_samples(residual: np.ndarray, step: int = 1, *, lag1: float | None = None) -> float:
    """AR(1) effective sample size of a residual (N,) or (N, C) taken every ``step`` samples:
    ``(n / step) (1 - r) / (1 + r)``, r the lag-``step`` autocorrelation
    (:func:`lag1_autocorrelation`), n the finite rows; at least 3. ``step`` = 1 is the plain
    AR(1) formula; :func:`sample_step` gives the step of a parallel-filtered dataset. ``lag1``:
    that autocorrelation when the caller has it already."""
    r = np.asarray(residual, dtype=float)
    n = int(np.isfinite(r.reshape(r.shape[0], -1)).all(axis=1).sum())
    a = lag1_autocorrelation(r, step) if lag1 is None else float(lag1)
    return max(n / max(1, int(step)) * (1.0 - a) / (1.0 + a), 3.0)


class _OuterProblem:
    """Variable-projection residual of the outer (nonlinear) search: for given nonlinear values,
    the residual of the inner linear LS. When the transforms leave the regressor inputs untouched
    (e.g. a delay shifts only the measurement) the regressor is factorised once (QR) and every
    evaluation is a projection; otherwise the inner LS is solved afresh."""

    def __init__(self, model: Model, ds: Dataset, valid: np.ndarray, names: list[str],
                 channel_scale="rms"):
        self.model, self.ds, self.valid, self.names = model, ds, valid, names
        nl = model.nonlinear_params()
        nominal = {p.name: p.nominal for p in nl}
        ev0 = model.evaluate(ds, nominal)
        ds0 = ev0.ds
        # probe away from the nominal point: do the transforms touch the regressor inputs?
        probe = {p.name: (0.5 * (p.nominal + p.upper) if np.isfinite(p.upper) else p.nominal + 1.0)
                 if p.upper != p.nominal else 0.5 * (p.nominal + p.lower) for p in nl}
        dsp = model.apply_nonlinear(ds, probe)
        self.constant = all(dsp.signals.get(k) is v for k, v in ds0.signals.items()) and \
            dsp.act_map is ds0.act_map and dsp.act_vel is ds0.act_vel
        phi, self.cols, self.y_known = ev0.phi, ev0.columns, ev0.y_known
        fit0 = solve_linear(phi, ev0.lhs, self.cols, valid=valid, bounded=False,
                            channel_scale=channel_scale)
        self.w = fit0.channel_scale
        if self.constant:
            a = weigh(self.w, phi)[valid].reshape(int(valid.sum()) * phi.shape[1], phi.shape[2])
            self.q = np.linalg.qr(a, mode="reduced")[0] if a.shape[1] else np.zeros((a.shape[0], 0))

    def residual(self, x) -> np.ndarray:
        values = dict(zip(self.names, np.ravel(x)))
        if self.constant:   # the regressor does not move: only the transformed measurement
            ds2 = self.model.apply_nonlinear(self.ds, values)
            b = weigh(self.w, ds2.y - self.y_known)[self.valid].reshape(-1)
            return b - self.q @ (self.q.T @ b)
        ev = self.model.evaluate(self.ds, values)
        b = weigh(self.w, ev.lhs)[self.valid].reshape(-1)
        if ev.phi.shape[2] == 0:       # a model of known parts only (a delay alone)
            return b
        a = weigh(self.w, ev.phi)[self.valid].reshape(-1, ev.phi.shape[2])
        # normal equations on scaled columns: cheap for the few parameters of an outer search
        sc = np.linalg.norm(a, axis=0)
        sc = np.where(sc > 0, sc, 1.0)
        a_s = a / sc
        try:
            theta = scipy.linalg.solve(a_s.T @ a_s, a_s.T @ b, assume_a="pos")
        except (np.linalg.LinAlgError, ValueError):
            theta = np.linalg.lstsq(a_s, b, rcond=None)[0]
        return b - a_s @ theta


def _fixed_theta_residual(model: Model, ds: Dataset, nl: Mapping[str, float], fit: LinearFit,
                          valid: np.ndarray) -> np.ndarray:
    ev = model.evaluate(ds, nl)
    return _weighted_residual(fit, ev.phi, ev.lhs, valid)


def evaluate(model: Model, ds: Dataset, params: Mapping[str, float]
             ) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Measured output aligned with the model, model output, and valid mask on a dataset.

    Returns:
        ``(y_meas (N, C), y_hat (N, C), valid (N,))``: ``y_meas`` is the measurement after the
        model's data transforms (e.g. shifted by an identified delay); compare it with ``y_hat``
        where ``valid``.
    """
    ev = model.evaluate(ds, params)
    return ev.ds.y, ev.output(params), ev.ds.valid & np.isfinite(ev.ds.y).all(axis=1)
