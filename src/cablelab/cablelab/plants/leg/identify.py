"""Staged identification of the hopping leg with the NMSE cost and k-fold cross-validation
(003 sec. 3.3-3.4, eq. 27-29; spec 003_leg.md sec. 6).

k is measured (605 N/m) and fixed. Stages:

1. flight segments (lift-off to touch-down) give d_f;
2. stance segments (touch-down to lift-off) give m and d_s;
3. with those fixed, apex-to-apex single strides give beta_td and beta_lo;
4. validation: whole-stride NMSE and apex height / time errors with and without the impact map.

Each segment starts from the measured state (z, and zdot filtered by the 3rd-order 15 Hz
zero-phase Butterworth of 003 sec. 3.3, applied per phase run so the impact jumps are not smeared
into the neighbouring phase) and is simulated open-loop with the measured torque. Stages 1-2 run
every segment and parameter set as one :func:`mujoco.rollout.rollout` batch of phase models
(passive stiffness / damping, ctrl = F_in of eq. 3 from the measured torque and height); stage 3
steps the event-located hybrid plant :class:`~cablelab.plants.leg.sim.LegSim`. The optimiser is
:func:`cablelab.fit.simulation.fit_simulation` (``mujoco.minimize.least_squares``) on the eq. 28
residual, per trajectory normalised, summed over trajectories (eq. 29).
"""
from __future__ import annotations

import dataclasses
import threading
from dataclasses import dataclass, field

import mujoco
import numpy as np

from ...conditioning import lowpass
from ...errors import CablelabError
from ...fit.simulation import fit_simulation
from ...effects.base import Param
from .hybrid import STANCE, LegParams, input_force
from .mjcf import build_mjcf
from .sim import DT, LegSim
from .strides import phase_runs, segments, strides

#: velocity filter of 003 sec. 3.3
FILTER_HZ, FILTER_ORDER = 15.0, 3

#: shortest phase segment used in a fit, s (E1 micro-flights of a few samples carry no information)
MIN_SEGMENT_S = 0.04

#: optimiser iterations of each CV fold started from the all-data fit (``warm``)
WARM_FOLD_ITER = 2

#: proposed physical bounds (spec sec. 6)
BOUNDS = {"m": (1.0, 2.5), "d_s": (0.0, 30.0), "d_f": (0.0, 10.0), "beta_td": (0.2, 1.0),
          "beta_lo": (0.8, 1.5)}
UNITS = {"m": "kg", "d_s": "N s/m", "d_f": "N s/m", "beta_td": "-", "beta_lo": "-"}


@dataclass
class HopRecord:
    """One measured hopping record at the control period: t (s), z (m, encoder), zd (m/s,
    differentiated, may be NaN), contact (0/1 or None), tau (N m)."""

    t: np.ndarray
    z: np.ndarray
    tau: np.ndarray
    contact: np.ndarray | None = None
    zd: np.ndarray | None = None
    zd_filt: np.ndarray = field(init=False, repr=False)

    def __post_init__(self):
        self.t = np.asarray(self.t, float)
        self.z = np.asarray(self.z, float)
        self.tau = np.asarray(self.tau, float)
        if self.contact is None:
            raise CablelabError("leg identification needs the contact switch (or an estimated phase)")
        self.contact = (np.asarray(self.contact, float) > 0.5).astype(int)
        self.zd_filt = filtered_velocity(self.t, self.z, self.contact)


def filtered_velocity(t: np.ndarray, z: np.ndarray, phase: np.ndarray) -> np.ndarray:
    """zdot: backward difference of z, then the zero-phase 3rd-order 15 Hz Butterworth of 003
    sec. 3.3, run on each phase run separately (the impact jumps stay sharp)."""
    v = np.empty_like(z)
    v[1:] = np.diff(z) / np.diff(t)
    v[0] = v[1]
    fs = 1.0 / float(np.median(np.diff(t)))
    out = v.copy()
    for a, b, _ in phase_runs(phase):
        if b - a > 12:
            out[a:b] = lowpass(v[a:b], fs, FILTER_HZ, FILTER_ORDER)
    return out


#: initial-state fit per phase: (samples, polynomial order); flight is a near-parabola
FIT_WINDOW = {0: (40, 2), 1: (25, 3)}


def start_state(t: np.ndarray, z: np.ndarray, a: int, n_fit: int = 25, order: int = 3,
                forward: bool = True) -> tuple[float, float]:
    """(z, zdot) at sample ``a`` from a least-squares polynomial fit of the measured z over the
    ``n_fit`` samples after (``forward``) or before it (polynomial ``order``): the initial state of a segment simulation.
    The filtered velocity is biased within a filter length of an impact (the edge of a phase
    run), a local fit of the encoder samples inside the phase is not."""
    sl = slice(a, a + n_fit) if forward else slice(max(a - n_fit + 1, 0), a + 1)
    tt = t[sl] - t[a]
    c = np.polynomial.polynomial.polyfit(tt, z[sl], order)
    return float(c[0]), float(c[1])


def impact_ratio_estimates(records: list[HopRecord], n_fit: int = 12) -> dict:
    """Direct estimates of beta_td and beta_lo (003 eq. 24): median over the contact-switch edges
    of zdot+ / zdot-, each from a quadratic fit of the encoder height on its side of the edge
    (edges with |zdot-| < 0.1 m/s are skipped: the ratio is undefined there). The start of the
    stage-3 fit."""
    ratios = {"beta_td": [], "beta_lo": []}
    for r in records:
        runs = phase_runs(r.contact)
        for (a0, b0, _), (a, b, ph) in zip(runs[:-1], runs[1:]):
            if b0 - a0 < n_fit or b - a < n_fit:
                continue
            _, vm = start_state(r.t, r.z, a - 1, n_fit, 2, forward=False)
            _, vp = start_state(r.t, r.z, a, n_fit, 2, forward=True)
            if abs(vm) > 0.1:
                ratios["beta_td" if ph == STANCE else "beta_lo"].append(vp / vm)
    return {k: float(np.clip(np.median(v), *BOUNDS[k])) for k, v in ratios.items() if v}


def stance_linear_estimate(records: list[HopRecord], p: LegParams, guard: int = 30,
                           cutoff_hz: float = 40.0) -> dict:
    """m and d_s by linear least squares on the stance samples (003 eq. 1 as an inverse model:
    ``F_in + k (z_0 - z) = m (zdd + g) + d_s zdot``, derivatives of the 40 Hz zero-phase filtered
    height, ``guard`` samples from every contact edge skipped). The start of the stage-2 fit."""
    from ...conditioning import derivatives

    rows, rhs = [], []
    for r in records:
        fs = 1.0 / float(np.median(np.diff(r.t)))
        _, zd, zdd = derivatives(r.z, fs, cutoff_hz, 4)
        for a, b in segments(r.contact, STANCE, guard):
            sl = slice(a, b)
            rows.append(np.c_[zdd[sl] + p.g, zd[sl]])
            rhs.append(input_force(r.tau[sl], r.z[sl], p) + p.k * (p.spring_rest - r.z[sl]) + p.F0)
    if not rows:
        return {}
    (m, d_s), *_ = np.linalg.lstsq(np.concatenate(rows), np.concatenate(rhs), rcond=None)
    return {"m": float(np.clip(m, *BOUNDS["m"])), "d_s": float(np.clip(d_s, *BOUNDS["d_s"]))}


def record_from_trajectory(traj) -> HopRecord:
    """A :class:`HopRecord` of the measured signals of a simulated
    :class:`~cablelab.plants.leg.sim.Trajectory`."""
    return HopRecord(traj.t, traj.z_meas, traj.tau, traj.contact)


# ----------------------------------------------------------------------------- segments

@dataclass
class Segment:
    """A piece of a record simulated from its first sample: measured z, zdot (filtered), F_in
    (N, from the measured torque and height; 0 in flight), torque, phase, time."""

    phase: int
    t: np.ndarray
    z: np.ndarray
    zd: np.ndarray
    f_in: np.ndarray
    tau: np.ndarray
    contact: np.ndarray
    x0: tuple = None  # (z, zdot) the simulation starts from

    def __post_init__(self):
        if self.x0 is None:
            self.x0 = (float(self.z[0]), float(self.zd[0]))

    @property
    def n(self) -> int:
        return len(self.t)


def phase_segments(records: list[HopRecord], phase: int, p: LegParams, margin: int = 3) -> list[Segment]:
    """Complete flight (0) or stance (1) runs of every record, ``margin`` samples trimmed at each
    impact (003 sec. 3.3: the start 'near the transition point')."""
    out = []
    for r in records:
        for a, b in segments(r.contact, phase, margin):
            if r.t[b - 1] - r.t[a] < MIN_SEGMENT_S:
                continue
            f = input_force(r.tau[a:b], r.z[a:b], p) if phase == STANCE else np.zeros(b - a)
            out.append(Segment(phase, r.t[a:b], r.z[a:b], r.zd_filt[a:b], f, r.tau[a:b],
                               r.contact[a:b], start_state(r.t, r.z, a, *FIT_WINDOW[phase])))
    return out


def stride_segments(records: list[HopRecord]) -> list[Segment]:
    """Apex-to-apex single strides of every record (003 sec. 3.3)."""
    out = []
    for r in records:
        for a, b in strides(r.t, r.z, r.contact):
            run_end = a + int(np.argmax(r.contact[a:] != r.contact[a])) if (r.contact[a:] != r.contact[a]).any() else len(r.t)
            fwd = run_end - a >= 25  # fit inside the apex's flight run
            x0 = start_state(r.t, r.z, a, 25 if fwd else 12, 2, forward=fwd) if fwd or a >= 12 else None
            out.append(Segment(-1, r.t[a:b], r.z[a:b], r.zd_filt[a:b], np.zeros(b - a), r.tau[a:b],
                               r.contact[a:b], x0))
    return out


# ----------------------------------------------------------------------------- simulation

def _phase_model(p: LegParams, phase: int, dt: float) -> mujoco.MjModel:
    """Phase model for batch rollouts: the slide-joint body with the phase's passive elements
    (spec sec. 4 variant (b)): stance ``jnt_stiffness = k``, ``qpos_spring = z_0``, damping d_s;
    flight stiffness 0, damping d_f. ctrl = F_in (+ F_0 in stance)."""
    m = build_mjcf(p, dt)
    m.jnt_stiffness[0] = p.k if phase == STANCE else 0.0
    m.qpos_spring[0] = p.spring_rest
    m.dof_damping[0] = p.d_s if phase == STANCE else p.d_f
    # flight: passive damping is a function of the state, so RK4 applies (spec sec. 4: "(b) +
    # RK4"); semi-implicit Euler would lag the position by g t dt / 2, as large as d_f's effect
    if phase != STANCE:
        m.opt.integrator = mujoco.mjtIntegrator.mjINT_RK4
    return m


def _initial_states(model, x0s) -> np.ndarray:
    """(S, nstate) FULLPHYSICS initial states of the slide-joint model for (z, zdot) pairs
    (one MjData for all: the state vector of this model differs only in qpos and qvel)."""
    d = mujoco.MjData(model)
    sig = mujoco.mjtState.mjSTATE_FULLPHYSICS
    out = np.empty((len(x0s), mujoco.mj_stateSize(model, sig)))
    for i, (z0, zd0) in enumerate(x0s):
        d.qpos[0], d.qvel[0] = z0, zd0
        mujoco.mj_getState(model, d, out[i], sig)
    return out


def simulate_phase_segments(segs: list[Segment], param_sets: list[LegParams], dt: float = DT,
                            buckets: int = 4) -> np.ndarray:
    """(k, S, n_max, 2) simulated [z, zdot] of every segment for every parameter set (NaN past a
    segment's end) by :func:`mujoco.rollout.rollout` (003 eq. 27); the segments are rolled out in
    ``buckets`` batches of similar length (padding every segment to the longest one cost 4x)."""
    lens = np.array([s.n for s in segs])
    out = np.full((len(param_sets), len(segs), int(lens.max()), 2), np.nan)
    order = np.argsort(lens)
    phases = {s.phase for s in segs}
    mods = [{ph: _phase_model(p, ph, dt) for ph in phases} for p in param_sets]
    xs = _initial_states(next(iter(mods[0].values())), [s.x0 for s in segs])
    for grp in np.array_split(order, min(buckets, len(segs))):
        if len(grp):
            sub = _rollout_segments([segs[i] for i in grp], param_sets, mods, xs[grp])
            out[:, grp, : sub.shape[2]] = sub
    return out


#: per thread, two MjData for :func:`mujoco.rollout.rollout` (two rollout threads: the 2 cores),
#: made once; every leg phase model has the same structure, so any of them can use these
_ROLLOUT = threading.local()


def _rollout_segments(segs: list[Segment], param_sets: list[LegParams], mods: list[dict],
                      xs: np.ndarray) -> np.ndarray:
    import mujoco.rollout

    n_max = max(s.n for s in segs)
    models, x0, ctrl = [], [], []
    for p, mod in zip(param_sets, mods):
        x0.extend(xs)
        for s in segs:
            m = mod[s.phase]
            models.append(m)
            u = np.zeros(n_max - 1)
            # the input over [t_n, t_n+1): mean of the measured samples at both ends (the
            # measured torque is known at the samples only; trapezoid = 2nd order)
            u[: s.n - 1] = 0.5 * (s.f_in[:-1] + s.f_in[1:]) + (p.F0 if s.phase == STANCE else 0.0)
            ctrl.append(u)
    if n_max < 2:
        return np.array(x0)[:, None, 1:3].reshape(len(param_sets), len(segs), 1, 2)
    if getattr(_ROLLOUT, "data", None) is None:
        _ROLLOUT.data = [mujoco.MjData(models[0]) for _ in range(2)]
    state, _ = mujoco.rollout.rollout(models, _ROLLOUT.data, np.array(x0), np.array(ctrl)[:, :, None])
    # FULLPHYSICS state = [time, qpos, qvel, ...]; row j is the state after step j + 1
    traj = np.concatenate([np.array(x0)[:, None, 1:3], state[:, :, 1:3]], axis=1)
    out = traj.reshape(len(param_sets), len(segs), n_max, 2)
    lens = np.array([s.n for s in segs])
    out[:, np.arange(n_max)[None, :] >= lens[:, None]] = np.nan
    return out


def simulate_stride(seg: Segment, p: LegParams, dt: float = DT, sim: LegSim | None = None) -> np.ndarray:
    """(n, 2) hybrid simulation of one apex-to-apex stride from its measured apex state, driven by
    the measured torque (applied while the simulated leg is in stance). ``sim``: a stepper of
    the same parameters to reuse (reset to the stride's start)."""
    if sim is None:
        sim = LegSim(p, seg.x0[0], seg.x0[1], phase=int(seg.contact[0]), dt=dt)
    else:
        sim.reset(seg.x0[0], seg.x0[1], phase=int(seg.contact[0]))
    out = np.empty((seg.n, 2))
    q, v = sim._q, sim._v
    for i in range(seg.n):
        out[i] = q[0], v[0]
        if i < seg.n - 1:
            sim.step(float(seg.tau[i]))
    return out


def simulate_strides(segs: list[Segment], param_sets: list[LegParams]) -> np.ndarray:
    n_max = max(s.n for s in segs)
    out = np.full((len(param_sets), len(segs), n_max, 2), np.nan)
    for k, p in enumerate(param_sets):
        sim = LegSim(p, segs[0].x0[0], segs[0].x0[1], dt=DT)
        for j, s in enumerate(segs):
            out[k, j, : s.n] = simulate_stride(s, p, sim=sim)
    return out


class SimulationMemo:
    """Memoised segment simulations: ``memo(simulate)(segs, param_sets)`` returns what
    ``simulate`` would and simulates only the (segment, parameter set) pairs not seen before.
    The k-fold fits of a stage start from the all-data fit, so their first evaluations and
    Jacobians, and the held-out validations, repeat simulations of the same segments with the
    same parameters."""

    def __init__(self, simulate):
        self.simulate = simulate
        self.store: dict = {}
        self.hits = self.misses = 0

    def __call__(self, segs: list[Segment], param_sets: list[LegParams]) -> np.ndarray:
        n_max = max(s.n for s in segs)
        out = np.full((len(param_sets), len(segs), n_max, 2), np.nan)
        for k, p in enumerate(param_sets):
            key = dataclasses.astuple(p)
            todo = [j for j, s in enumerate(segs) if (id(s), key) not in self.store]
            self.hits += len(segs) - len(todo)
            self.misses += len(todo)
            if todo:
                sim = self.simulate([segs[j] for j in todo], [p])[0]
                for i, j in enumerate(todo):
                    self.store[(id(segs[j]), key)] = sim[i, : segs[j].n]
            for j, s in enumerate(segs):
                out[k, j, : s.n] = self.store[(id(s), key)]
        return out


# ----------------------------------------------------------------------------- NMSE (eq. 28)

def _meas(segs: list[Segment]) -> np.ndarray:
    n_max = max(s.n for s in segs)
    y = np.full((len(segs), n_max, 2), np.nan)
    for j, s in enumerate(segs):
        y[j, : s.n, 0], y[j, : s.n, 1] = s.z, s.zd
    return y


def segment_metrics(segs: list[Segment], sim: np.ndarray) -> dict[str, np.ndarray]:
    """Per segment (S,) NMSE of position and velocity (003 eq. 28 terms, fractions), mean and
    max absolute errors (m, m/s)."""
    y = _meas(segs)
    e = sim - y
    dev = y - np.nanmean(y, axis=1, keepdims=True)
    nmse = np.nansum(e**2, axis=1) / np.nansum(dev**2, axis=1)
    return {"nmse_pos": nmse[:, 0], "nmse_vel": nmse[:, 1],
            "mae_pos": np.nanmean(np.abs(e[..., 0]), axis=1), "mae_vel": np.nanmean(np.abs(e[..., 1]), axis=1),
            "max_pos": np.nanmax(np.abs(e[..., 0]), axis=1), "max_vel": np.nanmax(np.abs(e[..., 1]), axis=1)}


def _fit(segs, simulate, base: LegParams, names: tuple[str, ...], max_iter: int = 30,
         x0: dict | None = None, covariance: bool = True) -> dict:
    """Minimise sum_i J_i (003 eq. 29) over ``names``: the measured and simulated trajectories are
    normalised per segment and channel, so the residual norm is the eq. 28 sum (up to a constant
    factor applied by :func:`fit_simulation`)."""
    y = _meas(segs)
    ok = np.isfinite(y)
    scale = np.sqrt(np.nansum((y - np.nanmean(y, axis=1, keepdims=True)) ** 2, axis=1, keepdims=True))
    y_n = np.where(ok, y / scale, 0.0)

    def run(sets):
        ps = [base.replace(**s) for s in sets]
        s = simulate(segs, ps)
        s = np.where(ok[None], s / scale[None], 0.0)
        return np.nan_to_num(s, nan=1e3).reshape(len(sets), -1, 1)

    start = {n: getattr(base, n) for n in names} if x0 is None else x0
    params = [Param(n, UNITS[n], float(np.clip(start[n], *BOUNDS[n])), *BOUNDS[n]) for n in names]
    res = fit_simulation(run, params, y_n.reshape(-1, 1), objective="nmse", max_iter=max_iter,
                         covariance=covariance)
    return res.params


def _folds(n: int, k: int, seed: int = 0) -> list[np.ndarray]:
    idx = np.random.default_rng(seed).permutation(n)
    return [np.sort(f) for f in np.array_split(idx, min(k, n))]


@dataclass
class StageResult:
    """One identification stage: parameter means and sd over the folds (Table 2 format), and the
    validation metrics of each held-out segment (Table 1 format)."""

    name: str
    params: dict
    sd: dict
    metrics: dict
    folds: int


def cross_validate(segs, simulate, base: LegParams, names, k: int, name: str, max_iter: int = 30,
                   warm: bool = False) -> StageResult:
    """k-fold CV (003 sec. 3.4): fit on k-1 folds, validate on the held-out one. With ``warm``,
    one fit on all segments first, then each fold starts from it (fewer iterations). The
    simulations are memoised (:class:`SimulationMemo`): a fold repeats the all-data fit's
    simulations of its segments at the start point, and the fold fits skip the covariance
    (their spread over the folds is the reported sd, as in 003 Table 2)."""
    simulate = SimulationMemo(simulate)
    x0 = _fit(segs, simulate, base, names, max_iter) if warm else None
    fits, mets = [], []
    for f in _folds(len(segs), k):
        held = set(f.tolist())
        train = [s for i, s in enumerate(segs) if i not in held]
        val = [segs[i] for i in f]
        pv = _fit(train, simulate, base, names, max_iter if not warm else WARM_FOLD_ITER, x0,
                  covariance=False)
        fits.append(pv)
        mets.append(segment_metrics(val, simulate(val, [base.replace(**pv)])[0]))
    params = {n: float(np.mean([f[n] for f in fits])) for n in names}
    sd = {n: float(np.std([f[n] for f in fits], ddof=1)) if len(fits) > 1 else 0.0 for n in names}
    metrics = {key: np.concatenate([m[key] for m in mets]) for key in mets[0]}
    return StageResult(name, params, sd, metrics, len(fits))


@dataclass
class Identification:
    """Result of :func:`identify`: the stages and the identified parameters."""

    flight: StageResult
    stance: StageResult
    impact: StageResult
    params: LegParams
    stride_metrics: dict
    apex: dict
    timings: dict = field(default_factory=dict)
    cpu_timings: dict = field(default_factory=dict)

    def table1(self) -> str:
        """Per-phase validation NMSE / MAE / max error in 003 Table 1's format (markdown)."""
        rows = ["| Phase | NMSE Mean | NMSE σ | Mean abs. error Mean | Mean abs. error σ | "
                "Max abs. error Mean | Max abs. error σ |", "| --- | --- | --- | --- | --- | --- | --- |"]
        for label, st in (("Stance", self.stance), ("Flight", self.flight)):
            for ch, unit in (("pos", "mm"), ("vel", "mm s^-1")):
                m = st.metrics
                rows.append(f"| {label} {'position' if ch == 'pos' else 'velocity'} | "
                            f"{100 * np.mean(m['nmse_' + ch]):.2f} (%) | {100 * np.std(m['nmse_' + ch]):.2f} | "
                            f"{1e3 * np.mean(m['mae_' + ch]):.1f} ({unit}) | {1e3 * np.std(m['mae_' + ch]):.1f} | "
                            f"{1e3 * np.mean(m['max_' + ch]):.1f} ({unit}) | {1e3 * np.std(m['max_' + ch]):.1f} |")
        return "\n".join(rows)

    def table2(self) -> str:
        """Identified parameters (003 Table 2 format): fold mean and standard deviation."""
        rows = ["| Parameter | Phase | Value | Standard deviation |", "| --- | --- | --- | --- |"]
        for st, phase in ((self.stance, "Stance"), (self.flight, "Flight"), (self.impact, "Impact")):
            for n in st.params:
                rows.append(f"| {n} | {phase} | {st.params[n]:.4g} {UNITS[n]} | {st.sd[n]:.3g} |")
        return "\n".join(rows)


def apex_errors(segs: list[Segment], sim: np.ndarray) -> dict:
    """Apex height (m) and apex time (s) absolute errors of the simulated strides against the
    measured ones, at the end apex of each stride (003 Fig. 11)."""
    dh, dt = [], []
    for j, s in enumerate(segs):
        tm, zm = _last_apex(s.t, s.z)
        ts, zs = _last_apex(s.t, sim[j, : s.n, 0])
        dh.append(abs(zs - zm))
        dt.append(abs(ts - tm))
    return {"height": np.array(dh), "time": np.array(dt)}


def _last_apex(t, z):
    """Highest sample in the last 40 % of a stride, refined by a parabola (the stride's end apex).
    A simulated stride whose apex falls past the end counts at the end sample."""
    from .strides import parabola_peak

    a = int(0.6 * len(z))
    i = a + int(np.nanargmax(z[a:]))
    if i <= 0 or i >= len(z) - 1:
        return float(t[i]), float(z[i])
    return parabola_peak(t[i - 1:i + 2], z[i - 1:i + 2])


def identify(records: list[HopRecord], base: LegParams | None = None, *, folds=(5, 10, 10),
             max_iter: int = 30, progress: bool = False) -> Identification:
    """The staged procedure of 003 sec. 3.4 on measured records (k fixed at ``base.k``)."""
    from tqdm import tqdm

    base = base or LegParams()
    start = base.replace(m=1.8, d_s=3.0, d_f=0.5, beta_td=0.8, beta_lo=1.0)
    import time

    bar = tqdm(total=4, desc="leg identification", disable=not progress)
    clock = [time.perf_counter(), time.process_time()]

    def lap(name):
        now, cpu = time.perf_counter(), time.process_time()
        timings[name], cpu_timings[name] = now - clock[0], cpu - clock[1]
        clock[0], clock[1] = now, cpu
        bar.update()

    timings: dict = {}
    cpu_timings: dict = {}
    fl = cross_validate(phase_segments(records, 0, base), simulate_phase_segments, start, ("d_f",),
                        folds[0], "flight", max_iter, warm=True)
    lap("flight")
    st_base = start.replace(d_f=fl.params["d_f"])
    st_base = st_base.replace(**stance_linear_estimate(records, st_base))
    st = cross_validate(phase_segments(records, STANCE, base), simulate_phase_segments, st_base,
                        ("m", "d_s"), folds[1], "stance", max_iter, warm=True)
    lap("stance")
    im_base = st_base.replace(**st.params)
    im_base = im_base.replace(**impact_ratio_estimates(records))
    strides_ = stride_segments(records)
    im = cross_validate(strides_, simulate_strides, im_base, ("beta_td", "beta_lo"), folds[2], "impact",
                        max_iter, warm=True)
    lap("impact")
    final = im_base.replace(**im.params)
    sims = simulate_strides(strides_, [final, final.no_impact()])
    whole = segment_metrics(strides_, sims[0])
    apex = {"full": apex_errors(strides_, sims[0]), "no_impact": apex_errors(strides_, sims[1]),
            "nmse_full": segment_metrics(strides_, sims[0]), "nmse_no_impact": segment_metrics(strides_, sims[1])}
    lap("validation")
    bar.close()
    return Identification(fl, st, im, final, whole, apex, timings, cpu_timings)


__all__ = ["HopRecord", "Identification", "Segment", "StageResult", "apex_errors", "cross_validate",
           "filtered_velocity", "identify", "phase_segments", "record_from_trajectory",
           "segment_metrics", "simulate_phase_segments", "simulate_stride", "simulate_strides",
           "stride_segments"]
