"""Leg measurements as a workbench :class:`~cablelab.dataset.Dataset` (inverse model, hybrid-aware).

The leg's equations (003 eq. 1, 23, 24) are linear in the parameters once the known forces are
moved to one side. With s = contact (1 stance), f = 1 - s:

    y = s (F_in + k (z_0 - z))                                   (known: eq. 3, measured k)
      = m (zdd + g) + d_s s zdot + d_f f zdot - F_0 s + ...       (effects)
        + sum_events m (1 - beta) zdot^- delta(t - t_e)           (impact map, eq. 24)

The velocity jump of eq. 24 is an impulse in the measured acceleration; its regressor is the
event's pre-impact velocity as a step, passed through the same filter and derivative as the
height (exact by linearity). The stance acceleration ``zdd s`` (effect ``phase_effective_mass``:
stance inertia m_s against the weighed mass m_f, ``m_s zdd + m_f g`` in stance) is the second
derivative of the height gained in stance ``D = int zdot s dt`` (the same filter and derivatives
as the height) less the jumps of ``zdot s`` at the edges (post-impact velocity at touch-down,
pre-lift-off velocity at lift-off, as steps): no impact impulse is counted as stance inertia. Every signal (y and all regressor bases) goes through the same
zero-phase low-pass ("parallel filtering"), so the switched terms and the impulses are smeared
identically on both sides. Regimes: phase (stance / flight) and time to the nearest transition.
"""
from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

from ...conditioning import derivatives, lowpass
from ...errors import CablelabError
from ...dataset import Dataset
from ...plant_interface import DatasetOptions
from . import topics
from .description import leg_of
from .identify import start_state
from .strides import phase_runs

#: default zero-phase low-pass of the inverse model (4th order): far above the 3 Hz stance
#: dynamics, low enough to tame the double derivative of a 0.09 mm encoder
CUTOFF_HZ, ORDER = 40.0, 4
#: samples dropped at both record ends (filter transients)
EDGE = 60


def event_steps(t: np.ndarray, z: np.ndarray, contact: np.ndarray) -> dict[str, np.ndarray]:
    """Step series ``sum_e zdot^-_e 1[t >= t_e]`` of touch-downs and lift-offs (m/s); the
    pre-impact velocity comes from a polynomial fit of z just before each contact edge."""
    return _event_steps(t, z, contact, 0.0, {})


def _event_steps(t, z, contact, adv: float, vcache: dict) -> dict[str, np.ndarray]:
    """:func:`event_steps` with the contact edges moved ``adv`` samples earlier (fractional: the
    step is linear across the sample period that holds the moved edge, exactly as the linear
    interpolation of the switch in :meth:`LegRecords.build`). The pre-impact velocity is fitted
    on the 12 samples before the moved edge (cached by that sample in ``vcache``)."""
    n_idx = np.arange(len(z), dtype=float)
    steps = {"touchdown": np.zeros_like(z), "liftoff": np.zeros_like(z), "touchdown_post": np.zeros_like(z)}
    for a, _, ph in phase_runs(contact)[1:]:
        a_true = a - adv                       # first sample at or after the true transition
        j = int(np.ceil(a_true - 1e-9)) - 1    # last sample before it
        if j < 7:
            continue
        if j not in vcache:
            vcache[j] = start_state(t, z, j, 12, 2, forward=False)[1]
        ramp = np.clip(n_idx - (a_true - 1.0), 0.0, 1.0)
        steps["touchdown" if ph == 1 else "liftoff"] += vcache[j] * ramp
        if ph == 1 and j + 13 <= len(z):       # post-impact velocity: fit on the 12 samples after
            key = ("post", j)
            if key not in vcache:
                vcache[key] = start_state(t, z, j + 1, 12, 2, forward=True)[1]
            steps["touchdown_post"] += vcache[key] * ramp
    return steps


@dataclass(eq=False)
class LegRecords:
    """The raw 1 kHz records a leg dataset was built from: ``(t, z, contact, tau)`` per record, the
    description and the velocity filter's cut-off. A dataset keeps it in ``signals["raw"]`` (one object, not a time
    series: subsets and the time-delay shift leave it alone) beside ``signals["row"]`` (int, each
    sample's row in the full dataset), so a transform that moves the phase (effect
    ``contact_delay``) rebuilds every phase-dependent signal on the whole records (the filters need
    the neighbouring samples) and then takes the rows of the samples at hand: a cross-validation
    fold gets the same values for its samples as the full record."""

    records: tuple
    description: object
    source: str = "data"
    cutoff_hz: float = CUTOFF_HZ
    _base: list = field(default_factory=list, repr=False)
    _cache: dict = field(default_factory=dict, repr=False)

    def __getstate__(self):          # pickled (e.g. to a fleet worker) without the caches
        return {**self.__dict__, "_base": [], "_cache": {}}

    def _bases(self) -> list[dict]:
        """Per record the parts that do not depend on the phase (computed once)."""
        if not self._base:
            p = leg_of(self.description).params(self.description.gravity)
            cut = float(self.cutoff_hz)
            for t, z, contact, tau in self.records:
                fs = 1.0 / float(np.median(np.diff(t)))
                _, zd, zdd = derivatives(z, fs, cut, ORDER)
                self._base.append({
                    "fs": fs, "zd": zd, "zdd": zdd, "zd_raw": np.gradient(z, 1.0 / fs),
                    "tau_over": tau / np.sqrt(np.maximum(4 * p.L**2 - z * z, 1e-12)),
                    "e": p.spring_rest - z, "k": p.k, "vcache": {}})
        return self._base

    def build(self, advance_s: float = 0.0) -> dict:
        """Every signal of the dataset with the contact switch advanced by ``advance_s`` s
        (``s(t) = switch(t + advance_s)``, linear interpolation between samples): ``{"y",
        "signals", "regimes"}``, the records concatenated.

        The switch enters every signal linearly (products with measured signals, linear
        filters, the event steps), so a fractional advance ``(i + f)`` samples is the blend
        ``(1 - f) B_i + f B_(i+1)`` of the builds at whole-sample advances, which are cached: an
        outer search over the advance costs one weighted sum per evaluation. The phase regimes
        come from the nearer whole-sample build."""
        d = max(float(advance_s), 0.0) * self._bases()[0]["fs"]
        i = int(np.floor(d + 1e-9))
        f = d - i
        if f < 1e-9:
            return self._whole(i)
        b0, b1 = self._whole(i), self._whole(i + 1)
        sig = {k: (1.0 - f) * v + f * b1["signals"][k] for k, v in b0["signals"].items()}
        return {"y": (1.0 - f) * b0["y"] + f * b1["y"], "signals": sig,
                "regimes": (b0 if f < 0.5 else b1)["regimes"]}

    def _whole(self, adv: int) -> dict:
        """:meth:`build` at an advance of ``adv`` whole samples (cached)."""
        if adv in self._cache:
            return self._cache[adv]
        g = self.description.gravity
        cut = float(self.cutoff_hz)
        parts = []
        for (t, z, contact, tau), b in zip(self.records, self._bases()):
            fs, n = b["fs"], len(t)
            s_raw = (np.asarray(contact, float) > 0.5).astype(float)
            s = np.concatenate([s_raw[adv:], np.full(min(adv, n), s_raw[-1])]) if adv else s_raw
            f_in = s * b["tau_over"]
            ev = _event_steps(t, z, s_raw.astype(int), adv, b["vcache"])
            e = b["e"]
            # height gained in stance, D = int zdot s dt (an edge interval counts half)
            dz = np.diff(np.asarray(z, float)) * 0.5 * (s[1:] + s[:-1])
            d_st = np.concatenate([[0.0], np.cumsum(dz)])
            # every phase-dependent basis through the same zero-phase low-pass in one call
            raw_cols = np.stack([f_in + s * b["k"] * e, b["zd_raw"] * s, b["zd_raw"] * (1 - s), s,
                                 1 - s, b["k"] * e**2 * s, b["k"] * e**3 * s, np.sign(b["zd"]),
                                 ev["touchdown"], ev["liftoff"], d_st,
                                 ev["touchdown_post"] - ev["liftoff"]], axis=1)
            f = lowpass(raw_cols, fs, cut, ORDER)
            acc = b["zdd"] + g
            dt = 1.0 / fs
            # zdd s: d2/dt2 of the filtered D minus the filtered jumps of zdot s at the edges
            acc_stance = np.gradient(np.gradient(f[:, 10], dt) - f[:, 11], dt)
            parts.append({
                "y": f[:, 0], "acc": acc, "zd_stance": f[:, 1], "zd_flight": f[:, 2], "stance": f[:, 3],
                "flight": f[:, 4], "e2": f[:, 5], "e3": f[:, 6], "sign": f[:, 7],
                "acc_stance": acc_stance, "impulse_td": np.gradient(f[:, 8], 1.0 / fs),
                "impulse_lo": np.gradient(f[:, 9], 1.0 / fs), "z": np.asarray(z, float), "zd": b["zd"],
                "contact": s, "f_in": f_in, "phase": np.where(s > 0.5, "stance", "flight"),
                "transition": np.where(_time_to_edge(s, fs) < 0.02, "within 20 ms of a transition",
                                       "away from transitions")})
        cat = {k: np.concatenate([q[k] for q in parts]) for k in parts[0]}
        out = {"y": cat.pop("y")[:, None],
               "regimes": {"phase": cat.pop("phase"), "transition": cat.pop("transition")},
               "signals": cat}
        per_build = sum(v.nbytes for v in cat.values()) + out["y"].nbytes
        keep = int(np.clip(CACHE_BYTES // max(per_build, 1), 2, CACHE_BUILDS))
        while len(self._cache) >= keep:
            self._cache.pop(next(k for k in self._cache if k != 0))
        self._cache[adv] = out
        return out


#: whole-sample builds kept by :class:`LegRecords` (0-20 ms at 1 kHz: 21), and at most about
#: this many bytes of them (a long record keeps fewer; the zero advance is always kept)
CACHE_BUILDS = 24
CACHE_BYTES = 200e6


def _time_to_edge(s: np.ndarray, fs: float) -> np.ndarray:
    """Time from every sample to the nearest phase edge of ``s`` (s; inf without an edge)."""
    edges = np.flatnonzero(np.diff(s > 0.5)) + 1
    n = len(s)
    if not len(edges):
        return np.full(n, np.inf)
    idx = np.arange(n)
    k = np.clip(np.searchsorted(edges, idx), 1, len(edges)) - 1
    nxt = np.minimum(k + 1, len(edges) - 1)
    return np.minimum(np.abs(idx - edges[k]), np.abs(idx - edges[nxt])) / fs


#: time between concatenated records on the dataset's time axis, s (a gap: nothing is
#: interpolated or shifted across it)
RECORD_GAP_S = 1.0


def dataset_from_records(records, description, options: DatasetOptions | None = None,
                         source: str = "data") -> Dataset:
    """Leg dataset from one or more raw 1 kHz records ``(t, z, contact, tau)`` (s, m, 0/1, N m).
    Each record is filtered on its own (``EDGE`` samples at its ends invalid) and the records are
    concatenated, later ones moved on the time axis to start ``RECORD_GAP_S`` after the previous
    one ends. ``options`` are unused: the leg filters with its own cut-off (:data:`CUTOFF_HZ`)."""
    recs = []
    for t, z, contact, tau in records:
        if contact is None:
            raise CablelabError(f"{source}: the leg dataset needs the phase (contact switch or estimated)")
        recs.append(tuple(np.asarray(x, float) for x in (t, z, contact, tau)))
    if not recs:
        raise CablelabError(f"{source}: no leg record")
    rates = [1.0 / float(np.median(np.diff(r[0]))) for r in recs]
    if max(rates) - min(rates) > 1e-6 * max(rates):
        raise CablelabError(f"{source}: leg records at different sample rates "
                            f"({min(rates):g} and {max(rates):g} Hz); resample them to one rate")
    raw = LegRecords(tuple(recs), description, source)
    built = raw.build(0.0)
    times, valid, t_next = [], [], None
    for t, *_ in recs:
        tt = t if t_next is None else t - t[0] + t_next
        times.append(tt)
        v = np.zeros(len(t), bool)
        v[EDGE:-EDGE] = True
        valid.append(v)
        t_next = tt[-1] + RECORD_GAP_S
    t = np.concatenate(times)
    sig = dict(built["signals"])
    zd = sig["zd"]
    sig["raw"], sig["row"] = raw, np.arange(len(t))
    return Dataset(plant="leg", t=t, y=built["y"], channels=("body",), units=("N",), signals=sig,
                   actuators=("body",), act_vel=zd[:, None], act_units=(("N", "m"),),
                   valid=np.concatenate(valid), regimes=dict(built["regimes"]),
                   inputs={"velocity": zd}, description=description, source=source)


def dataset_from_arrays(t, z, contact, tau, description, options: DatasetOptions | None = None,
                        source: str = "data") -> Dataset:
    """Leg dataset from raw 1 kHz arrays: t (s), z (m), contact (0/1), tau (N m)."""
    if contact is None:
        raise CablelabError(f"{source}: the leg dataset needs the phase (contact switch or estimated)")
    return dataset_from_records([(t, z, contact, tau)], description, options, source)


def advance_contact(ds: Dataset, advance_s: float) -> Dataset:
    """The dataset rebuilt with the contact switch advanced by ``advance_s`` s (the transform of
    effect ``contact_delay``): every phase-dependent signal, the output and the phase regimes,
    taken at the dataset's own rows (a fold subset stays a fold subset)."""
    raw = ds.signals.get("raw")
    if not advance_s or not isinstance(raw, LegRecords):
        return ds
    built = raw.build(advance_s)
    row = np.asarray(ds.signals["row"])
    return ds.replace(y=built["y"][row], signals={**ds.signals, **{k: v[row] for k, v in built["signals"].items()}},
                      regimes={**ds.regimes, **{k: v[row] for k, v in built["regimes"].items()}})


def check_bag(bag, description, options, series) -> list[str]:
    """Input checks before a fit (:func:`cablelab.bagcheck.check_bag`): say when the phase has
    to come from the height because the bag has no contact switch."""
    if bag.has(topics.CONTACT):
        return []
    return [f"{bag.path}: no /leg/contact in the bag; phase detected from the height "
            "(z < z_td - 0.5 mm, 20 ms dwell)"]


def dataset(bag, description, options: DatasetOptions) -> Dataset:
    """Leg dataset from a bag's ``/leg/joint_states`` (joint ``body`` height, ``motor`` torque) and
    ``/leg/contact``. Without the contact topic the phase comes from the height (live estimator
    rule) and :func:`check_bag` says so."""
    from .estimator import estimate_series

    js = bag.joint_state(topics.JOINT_STATES)
    if "body" not in js.names:
        raise CablelabError(f"{bag.path}: /leg/joint_states has no joint 'body' (has {js.names})")
    # a lock-stepped simulator resends its start state until the controller answers it: one
    # sample per stamp (the first)
    once = np.r_[True, np.diff(js.t) > 0] if len(js.t) else np.ones(0, bool)
    t_js = js.t[once]
    z = js.position[once, js.names.index("body")]
    tau = js.effort[once, js.names.index("motor")] if "motor" in js.names else np.zeros_like(z)
    tau = np.nan_to_num(tau)
    contact = None
    if bag.has(topics.CONTACT):
        c = bag.joint_state(topics.CONTACT)
        contact = np.interp(t_js, c.t, c.position[:, 0]) > 0.5
    if contact is None:       # (said as a warning of the input checks: check_bag below)
        leg = leg_of(description)
        contact = estimate_series(t_js, z, None, tau, leg.params(description.gravity))["phase"]
    return dataset_from_arrays(t_js, z, contact, tau, description, options, source=str(bag.path))
