"""Experiment design: a reference trajectory that makes named parameters identifiable.

A diagnosis that finds two parameters confounded (or one not excited) can only say "record
motion that excites them independently". This module designs that motion, the way robot
identification toolboxes do (Swevers et al., "Optimal robot excitation and identification",
IEEE T-RA 1997): every joint follows a finite Fourier series

    q_j(t) = c_j + w(t) s_j sum_k [a_jk / (k w_f) sin(k w_f t) - b_jk / (k w_f) cos(k w_f t)]

(base frequency w_f = 2 pi f_0, H harmonics; w(t) a smoothstep fade-in and fade-out so the
machine starts and ends at rest at c; a plant whose machine rests elsewhere when the reference
starts, its ``Exciter.start``, gets a quintic lead-in from there to c, as fast as the speed and
acceleration limits allow, within the requested duration), and the coefficients minimise the condition number of
the named parameters' information (:func:`condition`: unit-norm columns of the regressor of the
model that holds them, the plant's nominal model plus the effects they belong to, with the other
parameters eliminated), computed with the plant's own effects on the dataset the
plant builds from the designed motion (:class:`Exciter`). The machine's limits hold by
construction: each joint's deviation is scaled by the largest ``s_j`` that keeps it inside its
range (with a margin), its speed and its acceleration limits.

A plant offers experiment design by registering an :class:`Exciter` (:func:`register_exciter`):
its limits from the description and a ``motion_dataset(t, q, qd, qdd, description)``.
"""
from __future__ import annotations

import time
from dataclasses import dataclass, replace
from typing import Callable, Sequence

import numpy as np

from .errors import CablelabError

#: fade-in / fade-out of the designed motion, s
FADE_S = 2.0
#: share of each joint's half range the motion may use around the range's centre
RANGE_MARGIN = 0.9


@dataclass(frozen=True)
class Limits:
    """The machine's limits per joint (SI): position range, speed, acceleration; ``constraint``
    (optional) ``fn(q, qd, qdd) -> [violation lines]`` for what per-joint ranges cannot say (the
    CDPR's cables between their minimum and maximum tension). A plant with a constraint chooses
    its box, speeds and accelerations so that every motion inside them satisfies it (checked on
    the designed reference)."""

    joints: tuple
    lower: np.ndarray
    upper: np.ndarray
    speed: np.ndarray
    accel: np.ndarray
    constraint: Callable | None = None

    def check(self, q: np.ndarray, qd: np.ndarray, qdd: np.ndarray, tol: float = 1e-9) -> list[str]:
        """Violations (one line each) of a motion (N, n) against the limits; empty if none."""
        out = []
        for j, name in enumerate(self.joints):
            if q[:, j].min() < self.lower[j] - tol or q[:, j].max() > self.upper[j] + tol:
                out.append(f"{name}: position {q[:, j].min():.4g}..{q[:, j].max():.4g} outside "
                           f"[{self.lower[j]:.4g}, {self.upper[j]:.4g}]")
            if np.abs(qd[:, j]).max() > self.speed[j] * (1 + 1e-6) + tol:
                out.append(f"{name}: speed {np.abs(qd[:, j]).max():.4g} above {self.speed[j]:.4g}")
            if np.abs(qdd[:, j]).max() > self.accel[j] * (1 + 1e-6) + tol:
                out.append(f"{name}: acceleration {np.abs(qdd[:, j]).max():.4g} above {self.accel[j]:.4g}")
        if self.constraint is not None:
            out.extend(self.constraint(q, qd, qdd))
        return out


@dataclass(frozen=True)
class Exciter:
    """What a plant offers for experiment design.

    Args:
        limits: ``fn(description) -> Limits``.
        motion_dataset: ``fn(t, q, qd, qdd, description) -> Dataset``: the dataset the plant's
            effects see for a motion that follows the reference exactly (outputs zero).
        reference_topic: the plant's ``reference`` topic.
        base_hz: lowest frequency of the Fourier series; harmonics: number of harmonics.
        rate_hz: sample rate of the written reference.
        grid: samples per period of the highest harmonic on the design grid (the cost's); fewer
            for a plant whose dataset is costly per sample.
        trajectory: ``"joint"`` (trajectory_msgs/JointTrajectory of the limits' joints) or
            ``"pose"`` (trajectory_msgs/MultiDOFJointTrajectory of a level platform: the joints
            are its x, y, z).
        start: ``fn(description) -> (n,)``: where the machine rests when the reference starts
            (e.g. the simulator's start pose), or None: at the centre of the limits' box. The
            designed reference then begins with a lead-in from there (:func:`lead_in`).
        stacked: whether the dataset of motions stacked on one time axis keeps each motion's
            rows apart (one row per reference sample), so one evaluation serves the cost and
            its gradient; None: probed on two stacked motions.
        tune: ``fn(params) -> {field: value}``: fields of this exciter chosen by the named
            parameters (e.g. a family fast enough to show a delay, or slow and wide enough to show
            what the travel reveals); None: the same fields for every design.
        loaded: ``fn(description, values) -> description`` whose ``motion_dataset`` synthesises
            the measurement of the load a recording's fit found (``values``: its linear
            parameters), for a plant whose delay column re-forms the outputs from that
            measurement (``remeasure``; the CDPR's tensions scale with the moving mass); None:
            the described machine's.
    """

    limits: Callable
    motion_dataset: Callable
    reference_topic: str
    base_hz: float = 0.05
    harmonics: int = 5
    rate_hz: float = 100.0
    grid: float = 10.0
    trajectory: str = "joint"
    start: Callable | None = None
    stacked: bool | None = None
    tune: Callable | None = None
    loaded: Callable | None = None


_EXCITERS: dict[str, Exciter] = {}


def register_exciter(plant: str, exciter: Exciter) -> Exciter:
    _EXCITERS[plant] = exciter
    return exciter


def get_exciter(plant: str) -> Exciter:
    from .registry import get_plant

    get_plant(plant)  # importing the plant registers its exciter
    ex = _EXCITERS.get(plant)
    if ex is None:
        have = ", ".join(sorted(_EXCITERS)) or "none"
        raise CablelabError(f"plant {plant} offers no experiment design yet (plants with one: {have})")
    return ex


def _smoothstep(x: np.ndarray, length: float):
    """Quintic smoothstep from 0 (x <= 0) to 1 (x >= length), zero speed and acceleration at both
    ends, with its first and second derivatives in x."""
    s = np.clip(x / length, 0, 1)
    inside = (x > 0) & (x < length)
    w = s ** 3 * (10 - 15 * s + 6 * s * s)
    wd = np.where(inside, 30 * s * s * (1 - s) ** 2 / length, 0.0)
    wdd = np.where(inside, 60 * s * (1 - s) * (1 - 2 * s) / length ** 2, 0.0)
    return w, wd, wdd


#: peak speed and acceleration of the quintic smoothstep over a unit stroke in unit time
_PEAK_SPEED, _PEAK_ACCEL = 15.0 / 8.0, 10.0 / np.sqrt(3.0)


def lead_in(start, limits: Limits, rate_hz: float):
    """The quintic move at rest from ``start`` (n,) to the centre of the limits' box, the fastest
    the speed and acceleration limits allow on every joint (its length rounded up to the
    ``rate_hz`` grid): ``(length s, fn(t) -> (q, qd, qdd))`` (N, n) each, 0 <= t <= length."""
    q0 = np.asarray(start, float)
    q1 = 0.5 * (limits.lower + limits.upper)
    d = q1 - q0
    a = np.abs(d)
    length = float(np.max(np.maximum(_PEAK_SPEED * a / limits.speed, np.sqrt(_PEAK_ACCEL * a / limits.accel))))
    length = np.ceil(length * rate_hz - 1e-9) / rate_hz

    def fn(t):
        t = np.asarray(t, float)
        if length <= 0:                        # already at the centre
            return np.tile(q0, (len(t), 1)), np.zeros((len(t), len(q0))), np.zeros((len(t), len(q0)))
        w, wd, wdd = (v[:, None] for v in _smoothstep(t, length))
        return q0 + w * d, wd * d, wdd * d

    return length, fn


def _window(t: np.ndarray, duration: float):
    """Smoothstep fade-in over the first and fade-out over the last FADE_S seconds, with its first
    and second derivatives."""
    fade = min(FADE_S, duration / 4)

    a, ad, add = _smoothstep(t, fade)
    b, bd, bdd = _smoothstep(duration - t, fade)
    return a * b, ad * b - a * bd, add * b - 2 * ad * bd + a * bdd


def fourier_basis(t: np.ndarray, base_hz: float, harmonics: int, duration: float):
    """``(Bx, Bxd, Bxdd)`` (N, 2H): the windowed Fourier series is linear in its coefficients,
    ``x = Bx @ [a, b]`` (a: sine, b: cosine velocity amplitudes), starting at 0 at ``t[0]``."""
    om = 2 * np.pi * base_hz * np.arange(1, harmonics + 1)          # (H,)
    arg = t[:, None] * om[None, :]                                # (N, H)
    s, c = np.sin(arg), np.cos(arg)
    x = np.hstack([s / om, -c / om])
    x = x - x[:1]                                                  # start at the centre
    xd = np.hstack([c, s])
    xdd = np.hstack([-s * om, c * om])
    w, wd, wdd = (v[:, None] for v in _window(t, duration))
    return w * x, wd * x + w * xd, wdd * x + 2 * wd * xd + w * xdd


def fourier_motion(coef: np.ndarray, t: np.ndarray, base_hz: float, duration: float):
    """Unit-scale deviation ``(x, xd, xdd)`` (N, n_joints) of the windowed Fourier series with
    coefficients ``coef`` (n_joints, 2, H): a (sine) and b (cosine) velocity amplitudes."""
    n_j, _, h = coef.shape
    flat = coef.reshape(n_j, 2 * h).T
    return tuple(m @ flat for m in fourier_basis(t, base_hz, h, duration))


def _scale(x, xd, xdd, limits: Limits):
    """``(q, qd, qdd)`` of unit-scale deviations (..., N, n_joints) scaled per joint (and per
    leading index) to the largest amplitude the limits allow, around each range's centre."""
    centre = 0.5 * (limits.lower + limits.upper)
    half = 0.5 * (limits.upper - limits.lower) * RANGE_MARGIN
    with np.errstate(divide="ignore"):
        s = np.min(np.stack([half / np.max(np.abs(x), axis=-2),
                             limits.speed / np.max(np.abs(xd), axis=-2),
                             limits.accel / np.max(np.abs(xdd), axis=-2)]), axis=0)
    s = np.where(np.isfinite(s), s, 0.0)[..., None, :]
    return centre + s * x, s * xd, s * xdd


def scaled_motion(coef, t, limits: Limits, base_hz: float, duration: float):
    """``(q, qd, qdd)``: the Fourier deviation scaled per joint to the largest amplitude the
    limits allow, around the centre of each joint's range (limits hold by construction)."""
    return _scale(*fourier_motion(coef, t, base_hz, duration), limits)


def _weighted_columns(model, ds):
    """The model's regressor on ``ds`` as one matrix (valid rows, channels weighted by their
    regressor RMS so torques and forces weigh alike) and its parameter names."""
    phi, cols, _ = model.regressor(ds)
    ok = ds.valid & np.isfinite(phi).all(axis=(1, 2))
    a = phi[ok]
    rms = np.sqrt(np.mean(a ** 2, axis=(0, 2)))
    a = (a / np.where(rms > 0, rms, 1.0)[None, :, None]).reshape(-1, phi.shape[2])
    return a, [c.name for c in cols]


def condition(model, ds, params: Sequence[str] | None = None) -> float:
    """Condition number of the named parameters' information (``params``; None: all of the
    model's): with unit-norm columns and the model's other parameters eliminated (Schur
    complement of the information matrix), ``1 / lambda_min``. 1 when the named columns are
    orthogonal to each other and to the rest; large when a combination of them is (nearly) a
    combination of the other columns (confounded); inf when one is not excited. For one named
    parameter it is its variance inflation factor; for a pair with correlation rho and nothing
    else, (1 + |rho|) / (1 - rho^2)."""
    a, names = _weighted_columns(model, ds)
    if a.shape[1] == 0:
        return 1.0
    norms = np.linalg.norm(a, axis=0)
    if np.any(norms <= 1e-12 * max(norms.max(), 1e-300)):
        return float("inf")
    a = a / norms
    sel = [names.index(p) for p in params] if params else list(range(len(names)))
    rest = [i for i in range(len(names)) if i not in sel]
    a_s = a[:, sel]
    if rest:
        q, r = np.linalg.qr(a[:, rest])
        keep = np.abs(np.diag(r)) > 1e-10 * max(np.abs(np.diag(r)).max(), 1e-300)
        q = q[:, keep]
        a_s = a_s - q @ (q.T @ a_s)
    lam = np.linalg.eigvalsh(a_s.T @ a_s)
    return float(1.0 / lam[0]) if lam[0] > 1e-15 else float("inf")


#: nonlinear parameters a design can name, through their linearised column (:class:`Linearised`)
LINEARISED = ("tau",)


class Linearised:
    """A model with its delay ``tau`` (:mod:`cablelab.effects.delay`) as one more regressor column,
    linearised at ``tau0``: the sensitivity of the residual the fit sees to the delay. A fit
    evaluates the model on the dataset the delay transforms (``model.apply_nonlinear(ds, {"tau":
    tau})``: the motion at ``t - tau``, and on a plant with a ``remeasure`` hook its outputs
    re-formed from the raw measurement, the CDPR's wrench ``W(pose(t - tau)) t_meas(t)``); its
    residual is ``r(tau) = y(tau) - Phi(tau) theta - y_known(tau)``, so near ``tau0`` the data
    ask ``y - Phi theta - y_known = c (tau - tau0)`` with the column ``c = -d r / d tau``. On a plant
    whose outputs the delay leaves alone (the crane) that is ``d y / d tau = -d y0 / dt``, minus
    the time derivative of the model output ``y0 = Phi theta + y_known``; on the CDPR it is
    ``-W dt_meas/dt`` (the change of the measured tensions within tau) when the model explains
    the measurement. ``c`` is a central difference of ``r`` at ``tau0 +- h`` with ``h`` half the
    sample period (:meth:`step`). That column's information, jointly with the model's linear
    columns, is what :func:`condition` and :func:`block_conditions` measure (they only call
    ``regressor``). The stacked motions of :func:`_stacked_motion` are smooth across blocks
    (each starts and ends at rest at the same point), so the shift may cross them.

    Args:
        model: the model holding ``time_delay``.
        theta: values of the model's free linear parameters by name (missing: 0).
        tau0: the delay the column is evaluated at, s.
    """

    def __init__(self, model, theta: dict, tau0: float = 0.0):
        self.model, self.theta, self.tau0 = model, dict(theta), float(tau0)

    @property
    def effects(self):
        return self.model.effects

    @property
    def fixed(self):
        return self.model.fixed

    @staticmethod
    def step(t) -> float:
        """The difference step in tau, s: half the sample period. The delay interpolates every
        shifted signal linearly between samples, so within one sample interval the transformed
        dataset is linear in tau; a step up to one period then gives the interpolation's own
        slope (for a regressor linear in the shifted signals, the central difference of the
        samples, the same for any such step, with no truncation error), while a longer step
        would average the slope over neighbouring intervals. Half a period keeps ``tau0 +- h``
        inside the intervals on either side of ``tau0`` whatever its fraction of a sample."""
        d = np.diff(np.asarray(t, float))
        return 0.5 * float(np.median(d)) if d.size else 1e-3

    def residual(self, ds, tau: float):
        """``(r, valid)``: the fit's residual at the delay ``tau`` and the linear parameters at
        ``theta``, and where the delayed dataset is valid."""
        ev = self.model.evaluate(ds, {"tau": tau})
        theta = np.array([self.theta.get(c.name, 0.0) for c in ev.columns])
        return ev.lhs - ev.phi @ theta, np.asarray(ev.ds.valid, bool)

    def tau_column(self, ds) -> np.ndarray:
        """(N, C) ``c = -d r / d tau`` at ``tau0`` (NaN where a delayed dataset is not valid)."""
        h = self.step(ds.t)
        rp, okp = self.residual(ds, self.tau0 + h)
        rm, okm = self.residual(ds, self.tau0 - h)
        col = (rm - rp) / (2.0 * h)
        col[~(okp & okm)] = np.nan
        return col

    def regressor(self, ds):
        from .effects.base import Param

        phi, cols, y_known = self.model.regressor(self.model.apply_nonlinear(ds, {"tau": self.tau0}))
        col = self.tau_column(ds)
        return (np.concatenate([phi, col[:, :, None]], axis=2),
                list(cols) + [Param("tau", "s", self.tau0, doc="delay, linearised")], y_known)


def noise_of(model, ds) -> tuple[np.ndarray, float] | None:
    """``(sigma (C,), n_eff per second)`` of a recording: the RMS per channel of the residual of
    ``model``'s fit on ``ds`` (everything the model does not explain, noise and misfit) and the
    AR(1) effective samples per second of that residual (what the diagnosis' likelihood-ratio
    test counts, :func:`~cablelab.fit.identification.effective_samples`); None without ``ds`` or
    when the fit fails."""
    from .fit.identification import effective_samples, identify

    if ds is None:
        return None
    try:
        fit = identify(model, ds, on_deficient="hold")
    except CablelabError:
        return None
    r = fit.residual[np.isfinite(fit.residual).all(axis=1)]
    span = float(ds.t[-1] - ds.t[0]) if ds.n > 1 else 0.0
    if r.shape[0] < 3 or span <= 0:
        return None
    step = int(fit.extra.get("sample_step", 1))
    n_eff = np.mean([effective_samples(r[:, c], step) for c in range(r.shape[1])])
    return np.sqrt(np.mean(r ** 2, axis=0)), float(n_eff / span * r.shape[0] / ds.n)


def detectable_delay(model: "Linearised", ds, sigma, n_eff_per_s: float, *,
                     n_candidates: int = 1) -> dict:
    """The smallest delay the diagnosis calls significant on a recording of ``ds``'s motion with
    noise ``sigma`` (C,) per channel (:func:`noise_of`), from the delay's column (``model``,
    :class:`Linearised`) with the model's other columns projected out (what the fit cannot
    attribute to them), each channel whitened by its sigma (the fit's noise weights).

    A delay tau leaves ``tau c_perp`` in a channel's residual, so its held-out error falls by
    ``sqrt(1 + tau^2 s_c^2)`` (``s_c = rms(c_perp,c) / sigma_c``): the diagnosis' practical gain
    (:func:`~cablelab.diagnose.score.practical_gain`, the geometric mean over the channels it
    changes) reaches ``MIN_GAIN`` when ``mean_c log(1 + tau^2 s_c^2) = -2 log(1 - MIN_GAIN)``,
    whatever the record's length; its likelihood-ratio statistic ``sum_c n_eff log(1 + tau^2
    s_c^2)`` (:func:`~cablelab.diagnose.score.lr_significance`) passes ``alpha / m`` at the
    delay where it equals the chi^2(1) quantile, smaller the longer the record. The larger of the two
    is the smallest delay detectable.

    Returns:
        ``{"tau": s, "by_gain": s, "by_test": s, "snr": (C,) s_c in 1/s, "min_gain"}``; inf
        when the motion does not show a delay at all.
    """
    import scipy.optimize
    import scipy.stats

    from .diagnose.score import ALPHA, MIN_GAIN

    phi, _, _ = model.regressor(ds)
    ok = np.asarray(ds.valid, bool) & np.isfinite(phi).all(axis=(1, 2))
    sigma = np.asarray(sigma, float)
    live = sigma > 0
    a = phi[ok][:, live] / sigma[live][None, :, None]                      # whitened (n, C, P)
    n, c, p = a.shape
    col, rest = a[:, :, -1].reshape(-1), a[:, :, :-1].reshape(n * c, p - 1)
    if p > 1:
        q, r = np.linalg.qr(rest)
        keep = np.abs(np.diag(r)) > 1e-10 * max(np.abs(np.diag(r)).max(), 1e-300)
        q = q[:, keep]
        col = col - q @ (q.T @ col)
    out_snr = np.zeros(len(sigma))
    out_snr[live] = np.sqrt(np.mean(col.reshape(n, c) ** 2, axis=0)) if n else 0.0
    snr = out_snr[out_snr > 0]              # the channels the delay changes
    if snr.size == 0:
        return {"tau": float("inf"), "by_gain": float("inf"), "by_test": float("inf"), "snr": out_snr,
                "min_gain": MIN_GAIN}
    need_gain = -2.0 * np.log(1.0 - MIN_GAIN)
    n_eff = max(n_eff_per_s * float(ds.t[-1] - ds.t[0]), 3.0)
    need_test = scipy.stats.chi2.isf(ALPHA / max(n_candidates, 1), 1) / n_eff

    def solve(level, weight):   # the tau where weight * sum_c log(1 + tau^2 s_c^2) = level
        lo = np.sqrt(np.expm1(level / (weight * snr.size))) / snr.max()   # every channel the best
        hi = np.sqrt(np.expm1(level / weight)) / snr.max()                # the best channel alone
        f = lambda tau: weight * np.sum(np.log1p(tau ** 2 * snr ** 2)) - level
        if hi <= lo * (1 + 1e-12) or f(lo) >= 0:     # equal channels: lo is the root
            return float(lo)
        return float(scipy.optimize.brentq(f, lo, hi, xtol=1e-12 * hi, rtol=1e-10))

    by_gain = solve(need_gain, 1.0 / snr.size)
    by_test = solve(need_test, 1.0)
    return {"tau": max(by_gain, by_test), "by_gain": by_gain, "by_test": by_test, "snr": out_snr,
            "min_gain": MIN_GAIN}


def linear_values(model, ds, values: dict | None = None, columns_ds=None) -> dict:
    """The linear parameters' values :class:`Linearised` evaluates the model output at: ``values``
    where given, else a fit of ``model`` on ``ds`` (the recording that confounds them; parameters
    it does not excite held at their description or neutral values), else each parameter's
    description or neutral value (columns of ``columns_ds`` when there is no ``ds``)."""
    from .fit.identification import held_value, identify

    out = {}
    if ds is not None:
        try:
            out = dict(identify(model, ds, on_deficient="hold").params)
        except CablelabError:
            out = {}
    src = ds if ds is not None else columns_ds
    if not out and src is not None:
        for e in model.effect_objects:
            for p in e.columns(src):
                out[p.name] = held_value(model, src, p.name)
    out.update(values or {})
    return out


def model_for(plant, desc, params: Sequence[str], ds) -> tuple:
    """The plant's nominal model plus the effects that own ``params`` (names as the fit reports
    them, ``OF[slew]``), and the parameters' effects.

    Raises:
        CablelabError: a name that no applicable effect has (the message lists what exists).
    """
    from .effects import effects_for, get_effect
    from .model import Model

    base = list(plant.baseline(desc))
    owners = []
    known = {}
    for eid in base + [e for e in effects_for(plant.name) if e not in base]:
        eff = get_effect(eid, plant.name)
        for p in list(eff.columns(ds)) + list(eff.nonlinear):
            known.setdefault(p.name, eid)
    nonlinear = {p.name for eid in known.values() for p in get_effect(eid, plant.name).nonlinear}
    for name in params:
        if name not in known:
            raise CablelabError(f"--params {name!r}: no parameter of that name for plant {plant.name} "
                                f"(parameters: {', '.join(sorted(known))})")
        if name in nonlinear and name not in LINEARISED:
            raise CablelabError(f"--params {name!r}: a nonlinear parameter of {known[name]} (no regressor "
                                f"column whose information the design could condition); name linear "
                                f"parameters or {', '.join(LINEARISED)}")
        if known[name] not in base and known[name] not in owners:
            owners.append(known[name])
    return Model(plant.name, tuple(base + owners)), tuple(known[n] for n in params)


@dataclass
class Design:
    """Result of :func:`design`: the reference (t, q, qd, qdd), its limits, the condition numbers
    before (in the given dataset, or None) and after, the model, the seconds spent and the
    length of its lead-in from the machine's start (s, 0 without one)."""

    t: np.ndarray
    q: np.ndarray
    qd: np.ndarray
    qdd: np.ndarray
    limits: Limits
    params: tuple
    condition_before: float | None
    condition_after: float
    model: object
    seconds: float
    lead_in: float = 0.0
    detectable: dict | None = None

    def to_json(self) -> dict:
        out = {"params": list(self.params), "condition_before": self.condition_before,
               "condition_after": self.condition_after, "duration": float(self.t[-1] - self.t[0]),
               "model": list(self.model.effects), "joints": list(self.limits.joints),
               "seconds": self.seconds, "lead_in": self.lead_in}
        if self.detectable is not None:
            out["detectable"] = {k: (v.tolist() if isinstance(v, np.ndarray) else v)
                                 for k, v in self.detectable.items()}
        return out


def _stacked_motion(xs, basis, t, limits: Limits, shape):
    """The motions of coefficient vectors ``xs`` (k, n) one after the other on one time axis
    (each starts and ends at rest at the range's centre, so the stacked motion is smooth):
    ``(t, q, qd, qdd)`` of k blocks of ``len(t)`` samples (``basis``: :func:`fourier_basis`)."""
    step = t[1] - t[0] if len(t) > 1 else 1.0
    span = t[-1] - t[0] + step
    flat = np.asarray(xs).reshape(len(xs), shape[0], -1)           # (k, n_j, 2H)
    q, qd, qdd = _scale(*(np.einsum("nh,kjh->knj", m, flat) for m in basis), limits)
    t_all = (t[None, :] + span * np.arange(len(xs))[:, None]).ravel()
    return (t_all,) + tuple(m.reshape(-1, shape[0]) for m in (q, qd, qdd))


def stacked_dataset(ex: Exciter, xs, basis, t, limits: Limits, shape, desc, edges: bool = False):
    """The plant's dataset of the motions ``xs`` stacked by :func:`_stacked_motion`. ``edges``
    (a design naming the delay): each block's first and last sample left out, as a motion of
    its own has them (the delay's column there reaches beyond the motion: NaN), so every block
    is its motion's own and the cost's differences between blocks are the motions' (kept, one
    such row moved the CDPR's condition number from 1.076 to 1.006 on the design grid, and the
    optimiser's forward differences stopped it at its random start)."""
    ds = ex.motion_dataset(*_stacked_motion(xs, basis, t, limits, shape), desc)
    if edges:
        keep = np.ones(len(t), bool)
        keep[[0, -1]] = False
        ds = ds.replace(valid=np.asarray(ds.valid, bool) & np.tile(keep, len(xs)))
    return ds


def block_conditions(model, ds, blocks: int, params: Sequence[str]) -> np.ndarray:
    """:func:`condition` of each of ``blocks`` equal consecutive time blocks of ``ds`` at once
    (what one batched regressor evaluation of :func:`_stacked_motion` gives): the same
    weighting and Schur complement, from each block's information matrix (eigenvalues below
    1e-13 of the largest count as a rank deficiency of the other parameters)."""
    return block_terms(model, ds, blocks, params)[0]


def _schur(g, sel, rest):
    """Schur complement of the ``rest`` block of information matrices ``g`` (k, P, P) on ``sel``
    (pseudo-inverse: eigenvalues below 1e-13 of the largest count as a rank deficiency)."""
    s = g[:, sel][:, :, sel]
    if rest:
        grr, grs = g[:, rest][:, :, rest], g[:, rest][:, :, sel]
        w, v = np.linalg.eigh(grr)
        inv = np.where(w > 1e-13 * np.maximum(w[:, -1:], 1e-300), 1.0 / np.where(w > 0, w, 1.0), 0.0)
        proj = np.einsum("kri,ki,ksi->krs", v, inv, v)
        s = s - np.einsum("kri,krs,ksj->kij", grs, proj, grs)
    return s


def block_terms(model, ds, blocks: int, params: Sequence[str], info: str | None = None,
                sigma=None) -> tuple[np.ndarray, np.ndarray | None]:
    """:func:`block_conditions` and, for a parameter ``info``, its information per sample in
    each block with the model's other parameters eliminated, every channel whitened by ``sigma``
    (C,): ``1 / (n var)`` of its estimate on unit noise (what :func:`detectable_delay` turns
    into the smallest delay a recording shows); None without ``info``."""
    phi, cols, _ = model.regressor(ds)
    names = [c.name for c in cols]
    n, c, p = phi.shape
    phi = phi.reshape(blocks, n // blocks, c, p)
    ok = (np.asarray(ds.valid, bool).reshape(blocks, -1) & np.isfinite(phi).all(axis=(2, 3)))
    a = np.where(ok[:, :, None, None], phi, 0.0)
    cnt = np.maximum(ok.sum(axis=1), 1)[:, None]
    per_sample = None
    if info is not None:
        aw = (a / np.asarray(sigma, float)[None, None, :, None]).reshape(blocks, -1, p)
        i = names.index(info)
        gi = _schur(np.einsum("kmi,kmj->kij", aw, aw), [i], [j for j in range(p) if j != i])
        per_sample = np.maximum(gi[:, 0, 0], 0.0) / cnt[:, 0]
    rms = np.sqrt(np.sum(a ** 2, axis=(1, 3)) / (cnt * p))                   # (k, C)
    a = a / np.where(rms > 0, rms, 1.0)[:, None, :, None]
    a = a.reshape(blocks, -1, p)
    g = np.einsum("kmi,kmj->kij", a, a)
    d = np.sqrt(np.maximum(np.einsum("kii->ki", g), 0.0))                     # column norms
    dead = (d <= 1e-12 * np.maximum(d.max(axis=1, keepdims=True), 1e-300)).any(axis=1)
    d = np.where(d > 0, d, 1.0)
    g = g / d[:, :, None] / d[:, None, :]
    sel = [names.index(q) for q in params] if params else list(range(p))
    s = _schur(g, sel, [i for i in range(p) if i not in sel])
    lam = np.linalg.eigvalsh(0.5 * (s + np.swapaxes(s, 1, 2)))[:, 0]
    out = np.where(lam > 1e-15, 1.0 / np.where(lam > 1e-15, lam, 1.0), np.inf)
    return np.where(dead, np.inf, out), per_sample


def design(plant_name: str, desc, params: Sequence[str], *, duration: float = 60.0,
           before_ds=None, seed: int = 0, starts: int = 1, max_iter: int = 30,
           effects: Sequence[str] = (), fixed: dict | None = None,
           values: dict | None = None) -> Design:
    """Design an excitation of ``duration`` s for the named parameters (module doc).

    The cost (log condition number on a grid of 10 samples per period of the highest harmonic)
    and its forward-difference gradient are evaluated together: the k + 1 motions (the point and
    one step along each coefficient) are stacked on one time axis, so the plant's dataset and the
    model's regressor are built once per gradient (:func:`block_conditions`) instead of k + 1
    times.

    Args:
        plant_name, desc: the plant and its description (limits, geometry).
        params: parameter names as the fit reports them.
        before_ds: the dataset of the recording that confounds them (condition_before), or None.
        seed, starts: random starts of the local optimiser (the best is kept).
        effects, fixed: the model the designed run will be fitted with, when it is more than the
            nominal model and the parameters' effects: further effects (``--effects``, e.g. the
            CDPR's ``platform_inertia``, whose acceleration column a designed motion can confound
            with the named parameters) and known parameter values (``--fix``: no column, so the
            design spends no information on them). The condition numbers are those of this model.
        values: for a design naming the delay ``tau`` (linearised, :class:`Linearised`): the
            delay it is linearised at (``tau``, default 0) and values of the linear parameters
            the model output is evaluated at (default: the fit on ``before_ds``,
            :func:`linear_values`; on a plant with a ``remeasure`` hook, the fit on the designed
            motion's own dataset, whose measurement the plant synthesises).
    """
    import scipy.optimize

    from .registry import get_plant

    if not (np.isfinite(duration) and duration >= 4 * FADE_S):
        raise CablelabError(f"--duration {duration!r}: expected at least {4 * FADE_S:g} s")
    if not params:
        raise CablelabError("--params: name at least one parameter (e.g. --params 'OF[slew],m')")
    t0 = time.monotonic()
    plant = get_plant(plant_name)
    ex = get_exciter(plant_name)
    ex = replace(ex, **ex.tune(tuple(params))) if ex.tune is not None else ex
    lim = ex.limits(desc)
    total = duration
    lead_s, lead = lead_in(ex.start(desc), lim, ex.rate_hz) if ex.start is not None else (0.0, None)
    duration = total - lead_s               # the Fourier part, after the lead-in
    if duration < 4 * FADE_S:
        raise CablelabError(f"--duration {total!r}: expected at least {lead_s + 4 * FADE_S:g} s (the "
                            f"move from the machine's start to the design's centre takes {lead_s:g} s)")
    n_j, h = len(lim.joints), ex.harmonics
    shape = (n_j, 2, h)
    # design grid: ex.grid (10) samples per period of the highest harmonic
    fs = ex.grid * ex.base_hz * h
    t = np.arange(0.0, duration, 1.0 / fs)
    probe = ex.motion_dataset(t, *scaled_motion(np.ones(shape), t, lim, ex.base_hz, duration), desc)
    mdesc = desc          # the description the designed motion's datasets are built with
    model, _ = model_for(plant, desc, params, probe)
    from .model import Model

    if effects or fixed:
        model = Model(plant.name, tuple(dict.fromkeys(tuple(model.effects) + tuple(effects))), dict(fixed or {}))
        for name in params:
            if name in model.fixed:
                raise CablelabError(f"--params {name!r} is also fixed; name free parameters")
    if any(p in LINEARISED for p in params):
        vals = dict(values or {})
        tau0 = float(vals.pop("tau", 0.0))
        if getattr(plant, "remeasure", None) is not None:
            # the delay re-forms the outputs from the raw measurement the plant synthesises for a
            # designed motion (the CDPR: the described platform's feedforward tensions): the model
            # is evaluated where it explains that measurement, its fit on the motion's own
            # dataset. At the recording's values the difference between the recording's load and
            # the synthesised one would stay in the residual, and its change under a delay (the
            # wrench map's motion times that tension difference) is not the delay's column.
            own = Model(plant.name, tuple(model.effects), {**model.fixed, "tau": tau0})
            if before_ds is not None and ex.loaded is not None:
                # the measurement synthesised for the load the recording's fit found: the
                # delay's column (the tensions' change within tau) scales with the moving mass
                mdesc = ex.loaded(desc, linear_values(own, before_ds, vals))
                probe = ex.motion_dataset(t, *scaled_motion(np.ones(shape), t, lim, ex.base_hz, duration),
                                          mdesc)
            model = Linearised(model, linear_values(own, probe, vals), tau0)
        else:
            model = Linearised(model, linear_values(model, before_ds, vals, probe), tau0)
        if not np.any(np.abs(np.nan_to_num(model.tau_column(probe))) > 0):
            raise CablelabError("--params tau: the model's output is zero on a designed motion, so a "
                                "delay has nothing to shift; give the recording (BAG) whose fit "
                                "gives the model's parameters")
    # a delay's detection needs its column large against the noise, not only apart from the
    # others (the condition number is blind to the columns' size): the cost adds -log of the
    # delay's information per sample at the recording's noise (without BAG, noise proportional
    # to each channel's signal), i.e. log of the smallest delay the run shows
    info, sigma, noise = None, None, None
    if isinstance(model, Linearised):
        info = "tau"
        noise = noise_of(Model(plant.name, tuple(model.effects), {**model.fixed, "tau": model.tau0}),
                         before_ds)
        sigma = noise[0] if noise is not None else np.sqrt(np.nanmean(np.asarray(probe.y, float) ** 2, axis=0))
        pos = sigma[sigma > 0]
        sigma = np.where(sigma > 0, sigma, np.exp(np.mean(np.log(pos))) if pos.size else 1.0)
    n = n_j * 2 * h
    basis = fourier_basis(t, ex.base_hz, h, duration)

    # stacked evaluation when the plant's dataset keeps one sample per reference sample (not the
    # leg's, built per hop): checked once on two stacked motions
    stacked = ex.stacked if ex.stacked is not None else \
        ex.motion_dataset(*_stacked_motion(np.ones((2, n)), basis, t, lim, shape), mdesc).n == 2 * len(t)

    def conditions(xs):
        """(log condition numbers, log information per sample of ``info`` or None) of motions xs."""
        if stacked:
            ds = stacked_dataset(ex, xs, basis, t, lim, shape, mdesc, edges=isinstance(model, Linearised))
            c, per = block_terms(model, ds, len(xs), params, info, sigma)
        else:
            terms = [block_terms(model, ex.motion_dataset(
                t, *scaled_motion(x.reshape(shape), t, lim, ex.base_hz, duration), mdesc), 1, params,
                info, sigma) for x in xs]
            c = np.concatenate([a for a, _ in terms])
            per = None if info is None else np.concatenate([b for _, b in terms])
        cost = np.where(np.isfinite(c), np.log(np.where(np.isfinite(c), c, 1.0)), 1e3)
        if per is not None:
            cost = cost + np.where(per > 0, -0.5 * np.log(np.where(per > 0, per, 1.0)), 1e3)
        return cost

    def cost_grad(x):
        step = 1e-6 * np.maximum(1.0, np.abs(x))
        logc = conditions(np.vstack([x, x + np.diag(step)]))
        return float(logc[0]), (logc[1:] - logc[0]) / step

    rng = np.random.default_rng(seed)
    best = None
    for _ in range(max(1, starts)):
        x0 = rng.normal(size=n) / np.tile(np.arange(1, h + 1), n_j * 2)
        res = scipy.optimize.minimize(cost_grad, x0, jac=True, method="L-BFGS-B",
                                      options={"maxiter": max_iter})
        if best is None or res.fun < best.fun:
            best = res
    coef = best.x.reshape(shape)
    t_out = np.arange(0.0, total + 0.5 / ex.rate_hz, 1.0 / ex.rate_hz)
    k0 = int(round(lead_s * ex.rate_hz))      # the lead-in's samples, then the Fourier part from 0
    motion = scaled_motion(coef, t_out[k0:] - t_out[k0], lim, ex.base_hz, duration)
    if lead is not None:
        motion = [np.concatenate([a[:-1], b]) for a, b in zip(lead(t_out[:k0 + 1]), motion)]
    q, qd, qdd = motion
    # a start outside the box: the lead-in's positions are checked by the constraint alone
    check = replace(lim, lower=np.minimum(lim.lower, q[0]), upper=np.maximum(lim.upper, q[0]))
    bad = check.check(q, qd, qdd)
    if bad:   # a plant whose box does not guarantee its constraint: refuse, never write it
        raise CablelabError(f"designed reference breaks the machine's limits: {bad[0]}")
    after_ds = ex.motion_dataset(t_out, q, qd, qdd, mdesc)
    after = condition(model, after_ds, params)
    before = condition(model, before_ds, params) if before_ds is not None else None
    detect = None
    if isinstance(model, Linearised):     # the smallest delay the designed run shows, at BAG's noise
        if noise is not None:
            detect = detectable_delay(model, after_ds, *noise, n_candidates=len(plant.candidates(desc)))
            detect["noise"] = noise[0]
    return Design(t_out, q, qd, qdd, lim, tuple(params), before, after, model,
                  time.monotonic() - t0, lead_s, detect)


def write_reference(path, d: Design, exciter: Exciter, description_yaml: str | None = None,
                    *, overwrite: bool = False) -> None:
    """Write the designed reference as a bag of the plant's reference topic
    (trajectory_msgs/JointTrajectory: positions, velocities, accelerations), with the
    description when given."""
    from .bags import BagWriter

    with BagWriter(path, overwrite=overwrite) as w:
        if description_yaml:
            w.write_description(description_yaml)
        if exciter.trajectory == "pose":
            level = np.tile([0.0, 0.0, 0.0, 1.0], (len(d.t), 1))           # x, y, z, w
            w.write_multidof_trajectory(exciter.reference_topic, d.t, d.q, level, d.qd, None, d.qdd)
        else:
            w.write_joint_trajectory(exciter.reference_topic, d.t, list(d.limits.joints), d.q, d.qd,
                                     d.qdd)


def read_reference(path, topic: str, joints: Sequence[str]):
    """``fn(t) -> (q, qd, qdd)`` (N, n) interpolating a reference bag written by
    :func:`write_reference` (held at its last point after the end): what a controller plays.
    A pose reference (MultiDOFJointTrajectory) gives the platform's x, y, z (``joints`` unused)."""
    from .bags import open_bag

    bag = open_bag(path)
    if not bag.has(topic):
        raise CablelabError(f"{path}: no {topic} in the reference bag (topics: "
                            f"{', '.join(sorted(bag.topics)) or 'none'})")
    if bag.topics[topic].endswith("MultiDOFJointTrajectory"):     # a platform pose: x, y, z
        tr = bag.multidof_trajectory(topic)
        tt = tr.t - tr.t[0]
        cols = [np.nan_to_num(np.asarray(a, float)) for a in
                (tr.position, tr.linear_velocity, tr.linear_acceleration)]
    else:
        tr = bag.joint_trajectory(topic, list(joints))
        tt = tr.t - tr.t[0]
        cols = [np.asarray(a, float) if a is not None else np.zeros_like(tr.positions)
                for a in (tr.positions, tr.velocities, tr.accelerations)]

    def fn(t):
        t = np.atleast_1d(np.asarray(t, float))
        return tuple(np.stack([np.interp(t, tt, c[:, j]) for j in range(c.shape[1])], axis=1)
                     for c in cols)

    return fn


def excite_commands(ranking, plant: str, source: str, held=()) -> list[str]:
    """For every confounded pair of a ranking (``identifiability.confounded``) and the parameters
    the recording left unexcited (``held``, and candidates' ``held``), the exact
    ``cablelab excite`` command that designs the experiment separating them (one line each);
    a plant without experiment design gets one line saying so."""
    import shlex

    groups: list[tuple[str, ...]] = []
    for c in ranking:
        for r in (c.identifiability or {}).get("confounded", []):
            pair = tuple(sorted((r["param"], r["with"])))
            if pair not in groups:
                groups.append(pair)
        if c.held:
            g = tuple(c.held)
            if g not in groups:
                groups.append(g)
    if held and tuple(held) not in groups:
        groups.append(tuple(held))
    if not groups:
        return []
    try:
        get_exciter(plant)
    except CablelabError as exc:
        return [f"to separate {', '.join(' and '.join(g) for g in groups)}: {exc}"]
    bag = shlex.quote(str(source)) if source else "BAG"
    return [f"to separate {' and '.join(g)}: cablelab excite {bag} --params "
            f"{shlex.quote(','.join(g))} --duration 60 -o excite_{'_'.join(_slug(x) for x in g)}"
            for g in groups]


def _slug(name: str) -> str:
    return "".join(ch if ch.isalnum() else "_" for ch in name).strip("_")


__all__ = ["Design", "Exciter", "LINEARISED", "Limits", "Linearised", "block_conditions", "block_terms",
           "condition", "design", "detectable_delay", "excite_commands", "stacked_dataset", "fourier_basis", "fourier_motion", "get_exciter", "lead_in", "linear_values",
           "model_for", "noise_of", "read_reference", "register_exciter", "scaled_motion", "write_reference"]
