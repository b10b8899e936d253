"""Identification of the virtual-joint parameters (000 sec. 4, eq. 3-7; spec sec. 6).

Cost, 000 eq. 3/6/7: ``p̂ = argmax (1/N_e) sum_i R(x_m^i, x_s^i(p))``, ``0 <= p <= p̄`` (Table 5),
``R`` = mean Pearson rho over the output channels ``r_x, r_y, phi^z`` (000 eq. 4). The forward
model (000 eq. 5) is :func:`~cablelab.plants.suspended.mjcf.build_virtual` (``levelling="tendon"``)
integrated at 1 ms by :func:`mujoco.rollout.rollout` from the measured initial state; the
optimiser is :func:`cablelab.fit.simulation.fit_simulation` (``mujoco.minimize.least_squares``)
with objective ``pearson`` (residual with ``||r||^2 = 1 - R``) or the amplitude-aware ``nmse``
(003 eq. 28). The paper used fmincon active-set.

Each (experiment, channel) pair is one column of the fit, so the Pearson standardisation is per
experiment and channel exactly as in 000 eq. 7. Channels an experiment does not excite (standard
deviation below ``excite_factor`` x the pose noise) are left out: a Pearson value on noise is
meaningless (documented deviation from 000, which averages all three).

:func:`identify` also reports the parameters the data cannot determine
(:func:`identifiability`, from the finite-difference Jacobian of the residual at the optimum):
the condition number of the column-normalised Jacobian, its weak directions (right singular
vectors of singular values below ``weak`` x the largest: parameter combinations the data do not
see), the confounded pairs (|correlation| >= 0.9, :func:`cablelab.diagnose.identifiability.confounding`
with its thresholds) and the undetermined parameters: no sensitivity at all, a component >= 0.3
in a weak direction, a Gauss-Newton standard error (weak directions held fixed; inflated for
coloured residuals) above ``undetermined_rel`` of the Table 5 range, or confounded beyond 0.99
with an estimate below 5 standard errors. That is local non-identifiability only.

Discrete ambiguity, the compound pendulum's conjugate branch: a link's centre of mass at depth d
below its joint and at the centre of oscillation's conjugate ``d' = L_eq - d`` (``L_eq = J / (m l)``
of the whole mode, :func:`conjugate_depth`) swing with the same period, so a Pearson cost has a
basin at each. ``identify(..., starts=k)`` seeds the other branch from that
closed form plus ``k`` random starts inside the Table 5 bounds, fits locally from the start, the
conjugate and the best random seed, keeps the best, and reports the other basins that fit the
record as well within noise (``ambiguous_with``, with the paired block-bootstrap test of
:mod:`cablelab.diagnose.ambiguity`).
"""
from __future__ import annotations

import dataclasses
import types
from dataclasses import dataclass, field

import numpy as np

from ...diagnose.ambiguity import SPREAD_SIGMAS, paired_log_spread
from ...diagnose.identifiability import MIN_T, UNIDENTIFIABLE, confounding
from ...errors import CablelabError
from ...fit.simulation import SimulationFit, fit_simulation, objective_residual
from ...effects.base import Param
from .mjcf import build_truth, build_virtual
from .dataset import modal_inertias
from .params import IDENTIFIED, VirtualParams
from .reference import planar_bodies
from .sim import initial_state, simulate, truth_start
from .swing import swing_from_pose

__all__ = ["Experiment", "apply_values", "conjugate_depth", "basin_text", "values_of", "identifiability", "identified_params",
           "licas_experiments",
           "simulate_experiments", "identify", "validate", "Identification", "metrics",
           "CHANNELS"]

CHANNELS = ("r_x", "r_y", "yaw")


@dataclass
class Experiment:
    """One recorded experiment (000 sec. 5.3).

    Args:
        name: label. t: (N,) s at the output rate. y: (N, 3) measured [r_x m, r_y m, yaw rad].
        q0: start virtual joint positions by name (from the first measured pose).
        duration: s. every: simulation steps per output sample.
        arm_ctrl: (nstep, nu) arm servo references or None (arms held at 0).
        use: (3,) bool, channels excited in this experiment.
    """

    name: str
    t: np.ndarray
    y: np.ndarray
    q0: dict
    duration: float
    every: int = 10
    arm_ctrl: np.ndarray | None = None
    use: np.ndarray = field(default_factory=lambda: np.ones(3, bool))


def identified_params(variant: str = "licas", names=None) -> list[Param]:
    """Table 5 (★) parameters as :class:`Param` (nominal = p_0, bounds [0, p̄])."""
    out = []
    col = 1 if variant == "licas" else 2
    for row in IDENTIFIED:
        p0, hi = row[col]
        if names is None or row[0] in names:
            out.append(Param(row[0], "", p0, 0.0, hi, "000 Table 5"))
    if names is not None:
        missing = set(names) - {p.name for p in out}
        if missing:
            raise CablelabError(f"unknown suspended parameter(s) {sorted(missing)} (Table 5 rows: "
                                f"{', '.join(r[0] for r in IDENTIFIED)})")
    return out


def apply_values(p: VirtualParams, values: dict) -> VirtualParams:
    """Parameter set with Table 5 values (names of :data:`~.params.IDENTIFIED`) written in."""
    kw = {}
    I = [list(p.I7), list(p.I8), list(p.I9)]
    fv, fs = list(p.fv), list(p.fs)
    for k, v in values.items():
        v = float(v)
        if k in ("ixx", "iyy", "izz"):
            for row in I:
                row["xyz".index(k[1])] = v
        elif k.startswith("fv"):
            fv[int(k[2]) - 7] = v
        elif k.startswith("fs"):
            fs[int(k[2]) - 7] = v
        else:
            kw[k] = v
    return dataclasses.replace(p, I7=tuple(I[0]), I8=tuple(I[1]), I9=tuple(I[2]), fv=tuple(fv),
                               fs=tuple(fs), **kw)


def values_of(p: VirtualParams, names=None) -> dict:
    """The Table 5 parameters ``names`` (default all (★) rows) of a parameter set (inverse of
    :func:`apply_values`; ixx / iyy / izz are read from the link that turns about that axis:
    links 8 (J8, x), 9 (J9, y) and 7 (J7, z)). A warm start for :func:`identify`."""
    out = {}
    for row in IDENTIFIED:
        k = row[0]
        if names is not None and k not in names:
            continue
        if k == "ixx":
            v = p.I8[0]
        elif k == "iyy":
            v = p.I9[1]
        elif k == "izz":
            v = p.I7[2]
        elif k.startswith("fv"):
            v = p.fv[int(k[2]) - 7]
        elif k.startswith("fs"):
            v = p.fs[int(k[2]) - 7]
        else:
            v = getattr(p, k)
        out[k] = float(v)
    return out


def identifiability(fit: SimulationFit, params: list[Param], *, undetermined_rel: float = 0.25,
                    weak: float = 1e-3) -> dict:
    """What the data determine, from the Jacobian at the optimum of a :func:`fit_simulation`.

    Returns:
        ``{"condition", "stderr" {name: s.e.}, "correlation" (p, p), "confounded" [...],
        "weak_directions" [[(name, component), ...], ...], "undetermined" [names]}``; see the
        module docstring for the rules.
    """
    names = [q.name for q in params]
    if "jacobian" not in fit.extra:            # fit_simulation(covariance=False): nothing to judge by
        return {"condition": np.nan, "stderr": dict(fit.stderr), "correlation": None, "confounded": [],
                "weak_directions": [], "undetermined": []}
    J = np.asarray(fit.extra["jacobian"], float)
    r0 = np.asarray(fit.extra["residual"], float)
    p = len(names)
    s2 = float(r0 @ r0) / max(r0.size - p, 1)
    norms = np.linalg.norm(J, axis=0)
    live = norms > 1e-12 * max(float(norms.max()), 1e-300)
    idx = np.flatnonzero(live)
    if idx.size == 0:                          # the output moves with no parameter
        return {"condition": np.inf, "stderr": {n: np.inf for n in names}, "correlation": None,
                "confounded": [], "weak_directions": [], "undetermined": list(names)}
    _, S, Vt = np.linalg.svd(J[:, idx] / norms[idx], full_matrices=False)
    cond = float(S[0] / S[-1]) if S[-1] > 0 else np.inf
    strong = S >= weak * S[0]
    # covariance with the weak directions held fixed (truncated inverse): what the data pin down
    # once the combinations they do not see are set aside; those combinations are reported
    cov_n = (Vt[strong].T / S[strong] ** 2) @ Vt[strong] * s2
    cov = np.full((p, p), np.nan)
    cov[np.ix_(idx, idx)] = cov_n / np.outer(norms[idx], norms[idx])
    se = np.full(p, np.inf)
    se[idx] = np.sqrt(np.clip(np.diag(cov)[idx], 0, None)) * float(fit.extra.get("se_inflation", 1.0))
    stderr = dict(zip(names, map(float, se)))
    d = np.sqrt(np.clip(np.diag(cov), 0, None))
    with np.errstate(divide="ignore", invalid="ignore"):
        corr = np.nan_to_num(cov / np.outer(d, d))
    view = types.SimpleNamespace(linear=types.SimpleNamespace(names=tuple(names), cov=np.nan_to_num(cov),
                                                              cond=cond),
                                 stderr=stderr, params=fit.params)
    conf = confounding(view, names)["confounded"]
    weak_dirs = [[(names[idx[i]], float(v)) for i, v in enumerate(Vt[k]) if abs(v) >= 0.3]
                 for k in range(len(S)) if not strong[k]]
    in_weak = {n for d in weak_dirs for n, _ in d}
    confused = {r["param"] for r in conf if abs(r["correlation"]) >= UNIDENTIFIABLE
                and abs(fit.params[r["param"]]) < MIN_T * stderr[r["param"]]}
    und = [q.name for q, ok in zip(params, live) if not ok or stderr[q.name] > undetermined_rel * (q.upper - q.lower)
           or q.name in confused or q.name in in_weak]
    return {"condition": cond, "stderr": stderr, "correlation": corr, "confounded": conf,
            "weak_directions": weak_dirs, "undetermined": und}


#: the link depths with a conjugate branch, their link mass, and the swing modes they enter
#: (0: about x, J8, seen in r_y; 1: about y, J9, seen in r_x): link 9 turns with J8 and J9
CONJUGATE = {"l8z": ("m8", (0,)), "l9z": ("m9", (0, 1))}


def conjugate_depth(p: VirtualParams, name: str, axis: int = 0) -> float:
    """The other centre-of-mass depth of link 8 (``l8z``) or 9 (``l9z``) that gives the swing
    mode about ``axis`` (0: x, the q8 swing seen in r_y; 1: y, q9 in r_x) the same period.

    The mode is a compound pendulum about its joint: inertia ``J(d) = A + m d^2`` (the
    description's modal inertia, :func:`~.dataset.modal_inertias`) and static moment
    ``S(d) = B + m d`` (the links + everything hanging below at L). Its equivalent length
    ``L_eq = J / S`` (the centre of oscillation) is shared by the two roots of
    ``m d^2 - L_eq m d + (A - L_eq B) = 0``, whose sum is ``L_eq``: ``d' = L_eq - d``
    (for a lone link, ``B = 0``: ``d d' = A / m = k^2``).
    """
    if name not in CONJUGATE or axis not in CONJUGATE[name][1]:
        raise CablelabError(f"conjugate_depth: {name!r} about axis {axis} has no conjugate branch "
                            f"(use l8z about 0, l9z about 0 or 1)")
    d = float(getattr(p, name))
    b = planar_bodies(p)
    J = float(modal_inertias(p)[axis])
    moment = b["M_B"] * p.L + (b["mcA"] if axis == 0 else p.m9 * p.l9z + p.m_plat * p.L)
    return J / moment - d


def _z(y: np.ndarray) -> np.ndarray:
    return (y - y.mean(axis=0)) / np.where(y.std(axis=0) > 0, y.std(axis=0), 1.0)


def _same_fit(y_meas, a, b, objective: str) -> tuple[bool, float, float]:
    """Whether two simulated outputs fit ``y_meas`` equally within noise: the paired block
    bootstrap of :func:`cablelab.diagnose.ambiguity.paired_log_spread` on the objective's own
    scale (per-channel z-scores for Pearson, which ignores amplitude)."""
    f = _z if objective == "pearson" else (lambda v: v)
    d, sd = paired_log_spread(f(y_meas), f(a), f(y_meas), f(b))
    return abs(d) <= SPREAD_SIGMAS * sd, d, sd


def basin_text(ident: "Identification", units: dict | None = None) -> str:
    """One line for a human: the other basins that fit as well, or '' when there is none."""
    if not ident.ambiguous_with:
        return ""
    moved = sorted({k for o in ident.ambiguous_with for k, v in o["values"].items()
                    if not np.isclose(v, ident.values[k], rtol=0.05, atol=1e-6)})

    def show(vals):
        return ", ".join(f"{k} = {vals[k]:.3g}" for k in moved)
    others = "; ".join(show(o["values"]) for o in ident.ambiguous_with)
    return (f"ambiguous with {others}: fits the record as well as {show(ident.values)} within noise "
            f"(another basin of the cost, e.g. the conjugate branch of a compound pendulum); this "
            f"recording cannot tell them apart")


def _rest(p: VirtualParams) -> np.ndarray:
    return np.array(p.S, float) - [0.0, 0.0, p.L]


def simulate_experiments(p: VirtualParams, exps: list[Experiment], *, nthread: int = 2,
                         value_sets: list[dict] | None = None) -> list[list[np.ndarray]]:
    """Simulated outputs ``[set][experiment] -> (N, 3)`` of the virtual model for each value set
    (all sets and experiments in one rollout batch per distinct duration)."""
    sets = value_sets or [{}]
    params = [apply_values(p, v) for v in sets]
    out = [[None] * len(exps) for _ in sets]
    for d in sorted({e.duration for e in exps}):
        idx = [i for i, e in enumerate(exps) if e.duration == d]
        models, x0s, ctrls = [], [], []
        for pp in params:
            m = build_virtual(pp)
            for i in idx:
                models.append(m)
                x0s.append(initial_state(m, exps[i].q0))
                c = exps[i].arm_ctrl
                ctrls.append(np.zeros((int(round(d / m.opt.timestep)), m.nu)) if c is None else c)
        runs = simulate(models, np.array(x0s), d, np.array(ctrls), nthread=nthread)
        k = 0
        for s, pp in enumerate(params):
            rest = _rest(pp)
            for i in idx:
                r = runs[k]
                k += 1
                e = exps[i].every
                sw = swing_from_pose(r.pos[e - 1::e], r.quat[e - 1::e], pp.S, rest_pos=rest, rest_yaw=0.0)
                out[s][i] = np.stack([sw["r_x"], sw["r_y"], sw["yaw"]], axis=1)[:len(exps[i].t)]
    return out


def licas_experiments(p_gen: VirtualParams, *, plant: str = "virtual", duration: float = 10.0,
                      amp: float = 0.15, yaw0: float = 0.5, every: int = 10, pos_noise: float = 1e-3,
                      yaw_noise: float = np.deg2rad(0.5), seed: int = 0):
    """The 7 unforced LiCAS experiments of 000 sec. 5.3: identification (x, y, yaw displacement)
    and validation (x, y, yaw, xy), generated by the virtual model ``p_gen`` (``plant="virtual"``)
    or the 4-tendon truth plant (``"truth"``), with Gaussian pose noise.

    Returns:
        ``(identification, validation)`` lists of :class:`Experiment`.
    """
    rng = np.random.default_rng(seed)
    starts = [("id_x", 0, amp, 0), ("id_y", amp, 0, 0), ("id_yaw", 0, 0, yaw0),
              ("val_x", 0, 0.8 * amp, 0), ("val_y", 0.8 * amp, 0, 0), ("val_yaw", 0, 0, 0.8 * yaw0),
              ("val_xy", 0.7 * amp, 0.7 * amp, 0)]
    exps = []
    for name, sx, sy, yw in starts:
        if plant == "virtual":
            m = build_virtual(p_gen)
            q0 = {"J8": sx, "J11": -sx, "J9": sy, "J12": -sy, "J7": yw}
            run = simulate(m, initial_state(m, q0), duration)[0]
        elif plant == "truth":
            m = build_truth(p_gen)
            run = simulate(m, truth_start(m, p_gen, swing_x=sx, swing_y=sy, yaw=yw), duration)[0]
        else:
            raise CablelabError(f"licas_experiments plant {plant!r}: expected virtual or truth")
        pos = run.pos[every - 1::every]
        quat = run.quat[every - 1::every]
        sw = swing_from_pose(pos, quat, p_gen.S, rest_pos=_rest(p_gen), rest_yaw=0.0)
        y = np.stack([sw["r_x"], sw["r_y"], sw["yaw"]], axis=1)
        y = y + rng.normal(0, 1, y.shape) * [pos_noise, pos_noise, yaw_noise]
        noise = np.array([pos_noise, pos_noise, yaw_noise])
        use = y.std(axis=0) > 5 * np.maximum(noise, 1e-12)
        q0 = {"J8": sx, "J11": -sx, "J9": sy, "J12": -sy, "J7": yw}   # from the first pose
        exps.append(Experiment(name, run.t[every - 1::every], y, q0, duration, every, None, use))
    return exps[:3], exps[3:]


def metrics(y_meas: np.ndarray, y_sim: np.ndarray) -> dict:
    """Per channel: Pearson rho, NRMSE (RMS error / RMS of the measurement about its mean), MRE
    (mean |error| / mean |measurement|, the relative error of 000 Tables 1-2) and max |error|."""
    e = y_sim - y_meas
    ym = y_meas - y_meas.mean(0)
    ys = y_sim - y_sim.mean(0)
    rho = (ym * ys).sum(0) / np.sqrt((ym ** 2).sum(0) * (ys ** 2).sum(0) + 1e-300)
    return {"rho": rho, "nrmse": np.sqrt((e ** 2).mean(0)) / np.sqrt((ym ** 2).mean(0) + 1e-300),
            "mre": np.abs(e).mean(0) / (np.abs(y_meas).mean(0) + 1e-300),
            "max_abs": np.abs(e).max(0)}


@dataclass
class Identification:
    """Result of :func:`identify`: the fit, the full parameter set, mean R over the experiments
    (000 eq. 7), and the parameters the data do not determine."""

    fit: SimulationFit
    params: VirtualParams
    mean_R: float
    undetermined: list
    values: dict
    report: dict = field(default_factory=dict)     # :func:`identifiability`
    #: other basins that fit as well within noise: ``[{"values", "error", "difference", "spread"}]``
    ambiguous_with: list = field(default_factory=list)
    #: every local fit of a multi-start: ``[{"start", "values", "error"}]`` (best first)
    basins: list = field(default_factory=list)


def _stack(exps, ys):
    cols = [y[:, c] for e, y in zip(exps, ys) for c in range(3) if e.use[c]]
    n = min(len(c) for c in cols)
    return np.stack([c[:n] for c in cols], axis=1)


def identify(exps: list[Experiment], p_start: VirtualParams, names=None, *, objective: str = "pearson",
             start: dict | None = None, max_iter: int = 30, undetermined_rel: float = 0.25,
             progress: bool = False, nthread: int = 2, scan: dict | None = None, starts: int = 0,
             seed: int = 0) -> Identification:
    """Fit the Table 5 parameters ``names`` (default all (★) rows) to the experiments.

    Args:
        exps: identification experiments. p_start: parameter set for everything not fitted.
        objective: ``pearson`` (000 eq. 3-7) or ``nmse`` (amplitude-aware).
        start: start values by name (default Table 5 p_0), e.g. :func:`values_of` the repo set.
        scan: ``{name: values}``: before the local fit, try each value (the others at the start)
            in one rollout batch and start from the best by the objective. Pearson's cost has a
            basin per period slip, so a start whose yaw period is 25 % off (the repo k_p7 on the
            4-tendon truth plant: 2.25 s against 1.77 s) converges to "no yaw spring"; a scan of
            k_p7 over its Table 5 range puts the start in the right basin.
        starts: multi-start (0: off): ``starts`` random seeds (uniform in the Table 5 bounds,
            ``seed``) and the conjugate branch of every fitted ``l8z`` / ``l9z``
            (:func:`conjugate_depth`) are evaluated in one rollout batch; the local fit runs from
            the start, from each conjugate seed and from the best random seed if it beats them,
            and the best result is kept. ``ambiguous_with`` lists the other basins (another
            parameter by more than 5 % of its range) whose fit is equal within noise.
    """
    params = identified_params(p_start.variant, names)
    if start:
        params = [dataclasses.replace(q, nominal=float(np.clip(start.get(q.name, q.nominal), q.lower, q.upper)))
                  for q in params]
    y_meas = _stack(exps, [e.y for e in exps])

    def sim(value_sets):
        outs = simulate_experiments(p_start, exps, value_sets=value_sets, nthread=nthread)
        return np.stack([_stack(exps, o) for o in outs])

    if scan:
        base = {q.name: q.nominal for q in params}
        trials = [dict(base)]
        for name, vals in scan.items():
            if name not in base:
                raise CablelabError(f"identify: scan parameter {name!r} is not fitted ({', '.join(base)})")
            trials += [{**base, name: float(v)} for v in vals]
        ys = sim(trials)
        cost = [float(np.sum(objective_residual(y_meas, y, objective) ** 2)) for y in ys]
        best = trials[int(np.argmin(cost))]
        params = [dataclasses.replace(q, nominal=float(np.clip(best[q.name], q.lower, q.upper)))
                  for q in params]

    seeds = [{q.name: q.nominal for q in params}]
    if starts:
        # r_y shows the swing about x (axis 0), r_x the one about y (axis 1)
        axes = {a for e in exps for a, c in ((0, 1), (1, 0)) if e.use[c]}
        extra = _seeds(p_start, params, starts, seed, axes)
        n_conj = len(extra) - starts
        seeds += extra
        cost = [float(np.sum(objective_residual(y_meas, y, objective) ** 2)) for y in sim(seeds)]
        chosen = list(range(1 + n_conj))
        best_random = 1 + n_conj + int(np.argmin(cost[1 + n_conj:])) if len(seeds) > 1 + n_conj else None
        if best_random is not None and cost[best_random] < min(cost[i] for i in chosen):
            chosen.append(best_random)
        seeds = [seeds[i] for i in chosen]
    fits = []
    for s0 in seeds:
        x0 = [s0[q.name] for q in params]
        f = fit_simulation(sim, params, y_meas, objective=objective, max_iter=max_iter, progress=progress, x0=x0)
        fits.append((float(np.sum(objective_residual(y_meas, f.y_sim, objective) ** 2)), s0, f))
    fits.sort(key=lambda r: r[0])
    fit = fits[0][2]
    basins = [{"start": s0, "values": dict(f.params), "error": float(np.sqrt(c))} for c, s0, f in fits]
    def apart(a: dict, b: dict) -> bool:      # another basin: some parameter 5 % of its range away
        return any(abs(a[q.name] - b[q.name]) > 0.05 * (q.upper - q.lower) for q in params)

    ambiguous = []
    for c, _, f in fits[1:]:
        if not apart(f.params, fit.params) or any(not apart(f.params, o["values"]) for o in ambiguous):
            continue
        same, d, sd = _same_fit(y_meas, fit.y_sim, f.y_sim, objective)
        if same:
            ambiguous.append({"values": dict(f.params), "error": float(np.sqrt(c)), "difference": d,
                              "spread": sd})
    pearson_fit = 1.0 - float(np.sum(objective_residual(y_meas, fit.y_sim, "pearson") ** 2))
    report = identifiability(fit, params, undetermined_rel=undetermined_rel)
    return Identification(fit, apply_values(p_start, fit.params), pearson_fit, report["undetermined"],
                          dict(fit.params), report, ambiguous, basins)


def _seeds(p_start: VirtualParams, params: list[Param], k: int, seed: int, axes) -> list[dict]:
    """Multi-start seeds: the conjugate branch of each fitted l8z / l9z at the start values
    (clipped to its bounds) in each swing mode of ``axes`` the data show, then ``k`` uniform
    draws inside the bounds."""
    base = {q.name: q.nominal for q in params}
    p0 = apply_values(p_start, base)
    out = []
    for q in params:
        for axis in CONJUGATE.get(q.name, (None, ()))[1]:
            if axis in axes:
                out.append({**base, q.name: float(np.clip(conjugate_depth(p0, q.name, axis), q.lower, q.upper))})
    rng = np.random.default_rng(seed)
    lo, hi = np.array([q.lower for q in params]), np.array([q.upper for q in params])
    out += [dict(zip(base, map(float, lo + (hi - lo) * rng.random(len(params))))) for _ in range(k)]
    return out


def validate(p: VirtualParams, exps: list[Experiment], nthread: int = 2) -> list[dict]:
    """Per experiment: :func:`metrics` of the model ``p`` against the data, plus the channel mask."""
    ys = simulate_experiments(p, exps, nthread=nthread)[0]
    return [{"name": e.name, "use": e.use, **metrics(e.y[:len(y)], y)} for e, y in zip(exps, ys)]
