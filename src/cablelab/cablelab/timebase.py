"""Time-base validation of recorded stamps: gaps, clock jumps, stamps out of order, duplicates,
irregular rate, stamps in milliseconds, and the contiguous segments a fit may use.

Every verb that loads data runs :func:`check_stamps` on the header stamps of each topic the plant
reads (see :func:`cablelab.workbench.load_checked`). What is impossible (stamps that go back in
time) raises a one-line :class:`~cablelab.errors.CablelabError`; what is suspicious becomes a
warning line that the verbs print and put in their JSON ``"warnings"`` list. Gaps split the record
into contiguous segments: :func:`gap_mask` marks samples inside a gap (plus a filter margin at both
edges) invalid, so no fit uses values interpolated across a gap.

Definitions (``dt`` = successive header-stamp differences in log order, ``T`` = median positive
``dt``, s):

* backward step: ``dt < 0`` (a clock that jumps back, reversed stamps) -> error;
* duplicate: ``dt == 0`` -> warning (the repeated sample is dropped by the plant loaders);
* gap: ``dt > gap_factor * T`` -> warning, segments split there. A gap is a *clock jump* when
  the log (receive) time did not advance with the header stamp (``dt_log < dt / 2``), else a
  *recording gap*; a run of NaN/inf samples spanning more than ``gap_factor * T`` is a *NaN run*
  gap (short runs are bridged by the conditioning's interpolation);
* irregular rate: ``rate_factor * T < dt <= gap_factor * T`` or ``dt < T / rate_factor``;
* milliseconds: header span ~1000x the log span; or integer stamps with ``T >= 0.5`` s when
  nothing says they are seconds (log times that advance with the stamps while not being copies
  of them, or epoch stamps of a plausible date, 1973-2286) -> error; stamps beyond 1e11 (year
  5138 in s, 1973 in ms) with integer steps are ms. ``Limits(time_unit="s")`` (the verbs'
  ``--time-unit s``) trusts the stamps as seconds and skips this check.
"""
from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

from .errors import CablelabError


@dataclass(frozen=True)
class Limits:
    """Thresholds of the checks (relative to the median sample period ``T``).

    Attributes:
        gap_factor: a step longer than ``gap_factor * T`` is a gap (default 5).
        rate_factor: a step outside ``[T / rate_factor, rate_factor * T]`` is irregular (default 2).
        min_rate_hz: a median rate below this looks like stamps in ms or a broken clock (default 2 Hz).
        time_unit: ``"auto"`` (detect stamps in milliseconds) or ``"s"`` (the stamps are seconds,
            whatever they look like: a 1 Hz recording with integer stamps).
    """

    gap_factor: float = 5.0
    rate_factor: float = 2.0
    min_rate_hz: float = 2.0
    time_unit: str = "auto"


@dataclass(frozen=True)
class Gap:
    """A gap between samples ``index - 1`` and ``index`` (stamps ``start`` .. ``end``, s)."""

    index: int
    start: float
    end: float
    kind: str  # "recording gap" | "clock jump"

    @property
    def duration(self) -> float:
        return self.end - self.start


@dataclass
class TimebaseReport:
    """What :func:`check_stamps` found on one topic.

    Attributes:
        topic: topic name (or source label). samples: stamps checked.
        period: median positive period T, s. backward: steps with dt < 0; backward_max: the
        largest backward step, s; backward_at: stamp before the first one, s.
        duplicates: steps with dt == 0. gaps: :class:`Gap` list. irregular: irregular steps.
        nan_rows: samples with a non-finite value (dropped by the loaders).
        milliseconds: the stamps look like milliseconds.
        segments: ``(i0, i1)`` index ranges (i1 exclusive) of contiguous data between gaps.
    """

    topic: str
    samples: int
    period: float = float("nan")
    backward: int = 0
    backward_max: float = 0.0
    backward_at: float = float("nan")
    duplicates: int = 0
    gaps: list = field(default_factory=list)
    irregular: int = 0
    nan_rows: int = 0
    milliseconds: bool = False
    segments: list = field(default_factory=list)

    def warnings(self) -> list[str]:
        """One line per suspicious finding (empty when the time base is clean)."""
        out = []
        if self.gaps:
            longest = max(self.gaps, key=lambda g: g.duration)
            kinds = sorted({g.kind for g in self.gaps})
            out.append(f"{self.topic}: {len(self.gaps)} {' / '.join(kinds)}(s) in the record, longest "
                       f"{longest.duration:.3g} s at t = {longest.start:.6g} s; fitting {len(self.segments)} "
                       f"contiguous segments, samples across the gaps are not used")
        if self.duplicates:
            out.append(f"{self.topic}: {self.duplicates} repeated header stamps (samples dropped)")
        if self.irregular:
            out.append(f"{self.topic}: {self.irregular} of {max(self.samples - 1, 0)} sample periods "
                       f"differ from the median {self.period:.3g} s by more than a factor 2")
        if self.nan_rows:
            out.append(f"{self.topic}: {self.nan_rows} of {self.samples} samples have NaN/inf values "
                       f"(not used; runs longer than a gap split the record)")
        return out

    def as_dict(self) -> dict:
        return {"topic": self.topic, "samples": self.samples, "period": self.period,
                "backward": self.backward, "duplicates": self.duplicates, "irregular": self.irregular,
                "nan_rows": self.nan_rows, "milliseconds": self.milliseconds,
                "gaps": [{"start": g.start, "end": g.end, "duration": g.duration, "kind": g.kind}
                         for g in self.gaps],
                "segments": [[int(a), int(b)] for a, b in self.segments]}


def check_stamps(t, t_log=None, *, topic: str = "data", values=None,
                 limits: Limits = Limits()) -> TimebaseReport:
    """Check header stamps in log (arrival) order.

    Args:
        t: (N,) header stamps, s, in the order they were logged.
        t_log: optional (N,) log (receive) times, s: tells a clock jump from a recording gap and
            stamps in ms from a slow rate.
        topic: name used in messages. values: optional (N, ...) samples; rows with a non-finite
            value are counted in ``nan_rows`` (and ignored by the checks).
        limits: :class:`Limits`.
    Returns:
        :class:`TimebaseReport` (vectorised over N, no per-sample loop).
    """
    t = np.asarray(t, dtype=float).reshape(-1)
    ok = np.isfinite(t)
    nan_rows = int((~ok).sum())
    good = ok.copy()                  # rows usable as measurements (finite stamp and values)
    if values is not None:
        v = np.asarray(values, dtype=float).reshape(t.size, -1)
        bad_v = ~np.all(np.isfinite(v), axis=1) & ok
        nan_rows += int(bad_v.sum())
        good &= ~bad_v
    rep = TimebaseReport(topic=topic, samples=int(t.size), nan_rows=nan_rows)
    idx = np.flatnonzero(ok)
    ts = t[idx]
    if ts.size < 2:
        rep.segments = [(0, int(t.size))] if t.size else []
        return rep
    dt = np.diff(ts)
    pos = dt[dt > 0]
    T = float(np.median(pos)) if pos.size else float("nan")
    rep.period = T
    back = dt < 0
    rep.backward = int(back.sum())
    if rep.backward:
        k = int(np.argmin(dt))
        rep.backward_max = float(-dt[k])
        rep.backward_at = float(ts[np.flatnonzero(back)[0]])
    rep.duplicates = int((dt == 0).sum())
    if not np.isfinite(T):
        rep.segments = [(0, int(t.size))]
        return rep
    big = dt > limits.gap_factor * T
    rep.irregular = int((((dt > limits.rate_factor * T) & ~big) | ((dt > 0) & (dt < T / limits.rate_factor))).sum())
    dl = None
    seconds_by_log = False
    if t_log is not None:
        tl = np.asarray(t_log, dtype=float).reshape(-1)
        if tl.size == t.size:
            dl = np.diff(tl[idx])
            span_h, span_l = ts[-1] - ts[0], float(np.nanmax(tl[idx]) - np.nanmin(tl[idx]))
            if span_l > 0 and 300.0 < span_h / span_l < 3000.0:
                rep.milliseconds = True
            # a recorder's own clock that advances like the stamps (and is not a copy of them)
            independent = not np.allclose(tl[idx], ts, rtol=0.0, atol=1e-6)
            seconds_by_log = bool(independent and span_l > 0 and 0.5 < span_h / span_l < 2.0)
    if T >= 1.0 / limits.min_rate_hz and np.allclose(ts, np.round(ts)) and not seconds_by_log:
        epoch_seconds = 1e8 <= float(np.min(ts)) and float(np.max(ts)) < 1e10
        if not epoch_seconds:
            rep.milliseconds = True
    if limits.time_unit == "s":
        rep.milliseconds = False
    gi = np.flatnonzero(big)
    kinds = np.full(gi.size, "recording gap", dtype=object)
    if dl is not None and gi.size:
        kinds[dl[gi] < 0.5 * dt[gi]] = "clock jump"
    gaps = [Gap(int(idx[i + 1]), float(ts[i]), float(ts[i + 1]), str(k)) for i, k in zip(gi, kinds)]
    # a run of NaN/inf samples longer than a gap is a gap too (never interpolated across)
    gidx = np.flatnonzero(good)
    if gidx.size >= 2 and gidx.size < idx.size:
        tg = t[gidx]
        dg = np.diff(tg)
        nan_gap = np.flatnonzero((dg > limits.gap_factor * T) & (np.diff(gidx) > 1))
        pa, pb = np.searchsorted(idx, gidx[nan_gap]), np.searchsorted(idx, gidx[nan_gap + 1])
        cum = np.concatenate([[0], np.cumsum(big)])          # stamp gaps between positions pa..pb
        only_nan = cum[pb] - cum[pa] == 0
        gaps += [Gap(int(gidx[i + 1]), float(tg[i]), float(tg[i + 1]), "NaN run")
                 for i in nan_gap[only_nan]]
        gaps.sort(key=lambda g: g.index)
    rep.gaps = gaps
    cuts = [0] + [g.index for g in rep.gaps] + [int(t.size)]
    rep.segments = [(a, b) for a, b in zip(cuts[:-1], cuts[1:]) if b > a]
    return rep


def raise_if_impossible(rep: TimebaseReport, source: str = "") -> None:
    """One-line error for stamps that go back in time (a clock jump back, reversed stamps) or that
    are in milliseconds.

    Raises:
        CablelabError: naming the source, topic, count, where and how far.
    """
    where = f"{source}: " if source else ""
    if rep.milliseconds:
        raise CablelabError(
            f"{where}{rep.topic}: header stamps look like milliseconds (median period {rep.period:.3g} "
            f"'s' with integer stamps, or 1000x the log time span); write stamps in seconds "
            f"(import: --map time=0.001*COLUMN), or if they are seconds (e.g. a 1 Hz recording) "
            f"say so with --time-unit s")
    if rep.backward:
        raise CablelabError(
            f"{where}{rep.topic}: header stamps go back in time {rep.backward} time(s) (first after "
            f"t = {rep.backward_at:.6g} s, largest step back {rep.backward_max:.3g} s); the clock of "
            f"this recording is broken, fix the stamps or cut the recording")


def gap_mask(t, gaps, margin: float = 0.0) -> np.ndarray:
    """(N,) bool, False for the samples at ``t`` inside a gap widened by ``margin`` s at both
    edges (the conditioning filter's transient), True elsewhere."""
    t = np.asarray(t, dtype=float)
    keep = np.ones(t.shape, dtype=bool)
    if not gaps:
        return keep
    lo = np.array([g.start for g in gaps], dtype=float) - margin
    hi = np.array([g.end for g in gaps], dtype=float) + margin
    order = np.argsort(lo, kind="stable")        # O(N log G), not an (N, G) matrix
    lo, reach = lo[order], np.maximum.accumulate(hi[order])
    k = np.searchsorted(lo, t, side="left") - 1  # the last gap starting before t
    inside = (k >= 0) & (t < reach[np.maximum(k, 0)])
    return keep & ~inside


def interp_columns(t_new, t, x) -> np.ndarray:
    """Linear interpolation of (M, k) samples ``x`` at times ``t`` onto ``t_new`` (held at the
    ends): (len(t_new), k). Returns ``x`` itself when the times already agree."""
    t = np.asarray(t, float)
    x = np.asarray(x, float).reshape(len(t), -1)
    if len(t) == len(t_new) and np.array_equal(t, t_new):
        return x
    order = np.argsort(t)
    t, x = t[order], x[order]
    return np.stack([np.interp(t_new, t, x[:, j]) for j in range(x.shape[1])], 1)
