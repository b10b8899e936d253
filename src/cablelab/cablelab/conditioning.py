"""Data conditioning (002 sec. 5.1.3, 003 sec. 4; EMPS reference IDIM-LS).

Angle unwrapping, irregular sample times onto a uniform grid, zero-phase Butterworth low-pass
(``scipy.signal.butter`` + ``sosfiltfilt``), velocity and acceleration as central differences of
the filtered position, border samples dropped (the filter transients), optional decimation.
Every choice is a named field of :class:`Conditioning` with a documented default.
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from .errors import CablelabError
from .filters import lowpass


@dataclass(frozen=True)
class Conditioning:
    """Conditioning options.

    Attributes:
        cutoff_hz: low-pass cut-off for positions (and velocities), Hz. None = fs / 10
            (the EMPS reference: 100 Hz at 1 kHz).
        order: Butterworth order (applied forward and backward: zero phase, twice the order).
        effort_cutoff_hz: low-pass for the measured effort; None = not filtered, "same" = as
            positions (the parallel filtering of IDIM-LS).
        border: samples dropped at each end after filtering (filter transients), default 50.
        decimate: keep every k-th sample after filtering (k >= 1).
        unwrap: unwrap revolute angles (2 pi jumps).
        max_jitter: relative spread of sample periods above which times count as irregular and
            the signals are interpolated onto a uniform grid.
        parallel: when the automatic (quantization-aware) cut-off must go below the default
            and comes within :data:`~cablelab.velocity.PARALLEL_OVER_EXCITATION` x the motion's
            excitation bandwidth (``cutoff_hz`` None, ``effort_cutoff_hz`` None), keep the
            default for the derivatives and use the lowered cut-off as the parallel filter of
            the effort and of every regressor column (:mod:`cablelab.parallel_filter`, IDIM-LS)
            instead of filtering only the positions with it (which would attenuate the
            acceleration and sharpen the Coulomb column where the effort is not filtered).
            The automatic cut-off never goes below
            :data:`~cablelab.velocity.CUTOFF_OVER_EXCITATION` x the excitation bandwidth.
    """

    cutoff_hz: float | None = None
    order: int = 4
    effort_cutoff_hz: float | str | None = None
    border: int = 50
    decimate: int = 1
    unwrap: bool = True
    max_jitter: float = 0.05
    parallel: bool = True


def unwrap_angle(q: np.ndarray) -> np.ndarray:
    """Remove 2 pi jumps along time (axis 0), rad (002 sec. 5.1.3)."""
    return np.unwrap(np.asarray(q, dtype=float), axis=0)


def is_uniform(t: np.ndarray, max_jitter: float = 0.05) -> bool:
    """True if sample periods vary by less than ``max_jitter`` of their median."""
    dt = np.diff(t)
    if dt.size == 0:
        return True
    med = np.median(dt)
    return bool(med > 0 and np.all(dt > 0) and np.max(np.abs(dt - med)) <= max_jitter * med)


#: a step longer than this many grid periods may split the grid (as the time base's gap factor)
GAP_PERIODS = 5.0
#: a grid over the whole span may have at most this many points per sample
GRID_FACTOR = 4.0


def segment_grid(t_s: np.ndarray, rate_hz: float) -> np.ndarray:
    """Uniform grid at ``rate_hz`` over the sorted distinct stamps ``t_s``: one grid over the
    span if it has at most ``GRID_FACTOR x N`` points, else one per segment, the segments split
    at the longest steps > :data:`GAP_PERIODS` periods until that bound holds (or at all of them)."""
    dt = np.diff(t_s)
    cut = np.zeros(0, dtype=np.int64)
    excess = (t_s[-1] - t_s[0]) * rate_hz + 1 - GRID_FACTOR * t_s.size
    if excess > 0:
        cand = np.flatnonzero(dt > GAP_PERIODS / rate_hz)
        cand = cand[np.argsort(-dt[cand], kind="stable")]
        saved = np.cumsum(dt[cand] * rate_hz - 1)
        k = min(int(np.searchsorted(saved, excess)) + 1, cand.size)
        cut = np.sort(cand[:k]) + 1
    first = np.concatenate([[0], cut])
    last = np.concatenate([cut - 1, [t_s.size - 1]])
    t0 = t_s[first]
    counts = np.floor((t_s[last] - t0) * rate_hz + 1e-9).astype(np.int64) + 1
    offsets = np.concatenate([[0], np.cumsum(counts)[:-1]])
    k = np.arange(int(counts.sum())) - np.repeat(offsets, counts)
    return np.repeat(t0, counts) + k / rate_hz


def uniform_grid(t: np.ndarray, *signals: np.ndarray, rate_hz: float | None = None):
    """Resample irregularly sampled signals onto a uniform time grid (linear interpolation).

    Non-increasing / duplicate stamps are sorted and merged; NaN samples are skipped per column.
    The grid is bounded by the data, not by the stamps: if one uniform grid over the whole span
    would have more than :data:`GRID_FACTOR` x N points (e.g. a forward clock jump of 1e6 s), it
    is split at the longest gaps (steps longer than :data:`GAP_PERIODS` periods) until it has no
    more, each segment getting its own uniform grid from its first stamp (at most
    ``GAP_PERIODS x N + segments`` points whatever the stamps say; the samples next to a gap are
    masked by :func:`cablelab.timebase.gap_mask`).

    Args:
        t: (N,) sample times, s.
        signals: arrays (N,) or (N, k).
        rate_hz: grid rate; default 1 / median positive period.
    Returns:
        ``(t_uniform, [signals on the grid])``.
    """
    t = np.asarray(t, dtype=float)
    order = np.argsort(t, kind="stable")
    t_s = t[order]
    keep = np.concatenate([[True], np.diff(t_s) > 0])
    t_s = t_s[keep]
    if t_s.size < 2:
        raise CablelabError("fewer than 2 distinct sample times")
    if rate_hz is None:
        rate_hz = 1.0 / np.median(np.diff(t_s))
    tu = segment_grid(t_s, rate_hz)
    n = tu.size
    out = []
    for s in signals:
        s = np.asarray(s, dtype=float)[order][keep]
        s2 = s.reshape(s.shape[0], -1)
        cols = []
        for c in range(s2.shape[1]):  # per column (a handful), vectorised over time
            ok = np.isfinite(s2[:, c])
            cols.append(np.interp(tu, t_s[ok], s2[ok, c]) if ok.sum() >= 2 else np.full(n, np.nan))
        out.append(np.stack(cols, axis=1).reshape((n,) + s.shape[1:]))
    return tu, out


def derivatives(x: np.ndarray, fs: float, cutoff_hz: float | None, order: int = 4,
                method: str = "central"):
    """Filtered signal and its first two time derivatives.

    Args:
        method: ``"central"`` (central differences: exact enough while the motion stays far
            below the sample rate; their gain sin(w T) / (w T) is 0.86 for the velocity and 0.74
            for the acceleration of a 1.5 Hz motion sampled at 10 Hz) or ``"spline"`` (the
            derivatives of the quintic spline through the filtered samples: unbiased up to a
            few samples per period, used for slow recordings, see :func:`motion_cutoff`).
    Returns:
        ``(x_f, xd, xdd)`` each shaped like ``x`` (units x, x/s, x/s^2).
    """
    xf = lowpass(x, fs, cutoff_hz, order) if cutoff_hz else np.asarray(x, dtype=float)
    dt = 1.0 / fs
    if method == "spline" and xf.shape[0] > 6:
        from scipy.interpolate import make_interp_spline

        sp = make_interp_spline(np.arange(xf.shape[0]) * dt, xf, k=5, axis=0)
        return xf, sp.derivative(1)(np.arange(xf.shape[0]) * dt), sp.derivative(2)(np.arange(xf.shape[0]) * dt)
    xd = np.gradient(xf, dt, axis=0)
    xdd = np.gradient(xd, dt, axis=0)
    return xf, xd, xdd


def default_cutoff(fs: float, opts: Conditioning) -> float:
    return float(opts.cutoff_hz) if opts.cutoff_hz else fs / 10.0


#: the automatic cut-off may rise up to this fraction of the sample rate (below Nyquist, fs / 2)
MAX_CUTOFF_FRACTION = 0.4


def motion_cutoff(q: np.ndarray, fs: float, default_hz: float, order: int = 4,
                  source: str = "data") -> tuple[float, list[str]]:
    """The default cut-off, raised when it would filter the motion itself out (slow recordings).

    The motion's excitation bandwidth (:func:`cablelab.velocity.excitation_bandwidth`) is
    measured through the default filter; when it fills that filter (above
    ``default_hz / CUTOFF_OVER_EXCITATION``), it is measured again through a filter at
    :data:`MAX_CUTOFF_FRACTION` x fs, and the cut-off becomes
    ``CUTOFF_OVER_EXCITATION x`` that bandwidth (at most ``MAX_CUTOFF_FRACTION x fs``). At the
    EMPS rate (1 kHz, motion below 10 Hz) nothing changes; at 10 Hz a 1.5 Hz motion gets 3 Hz
    instead of 1 Hz.

    Returns:
        ``(cut-off Hz, warning lines)``: a warning when even the highest cut-off is below
        ``CUTOFF_OVER_EXCITATION x`` the motion's band (the recording is too slow for its motion:
        accelerations are not resolved).
    """
    from .velocity import CUTOFF_OVER_EXCITATION, excitation_bandwidth

    f_exc = excitation_bandwidth(q, fs, default_hz, order)
    if not f_exc * CUTOFF_OVER_EXCITATION > default_hz:
        return default_hz, []
    top = MAX_CUTOFF_FRACTION * fs
    f_exc = max(f_exc, excitation_bandwidth(q, fs, top, order))
    cut = min(max(default_hz, CUTOFF_OVER_EXCITATION * f_exc), top)
    warnings = []
    if CUTOFF_OVER_EXCITATION * f_exc > top:
        warnings.append(
            f"{source}: the motion reaches {f_exc:.3g} Hz, too close to the Nyquist frequency "
            f"({fs / 2:.3g} Hz) of this {fs:.3g} Hz recording: velocities and accelerations are not "
            f"resolved (filtered at {cut:.3g} Hz) and the fitted parameters are biased; record at "
            f"{2.5 * CUTOFF_OVER_EXCITATION * f_exc:.3g} Hz or more")
    return cut, warnings


def condition_motion(t: np.ndarray, q: np.ndarray, effort: np.ndarray,
                     opts: Conditioning = Conditioning(), *, revolute=False,
                     qd: np.ndarray | None = None, source: str = "data") -> dict:
    """Condition joint positions (and optional measured velocities) and efforts.

    Args:
        t: (N,) times, s; q: (N,) or (N, k) positions; effort: (N,) or (N, m) efforts.
        opts: :class:`Conditioning`. revolute: bool or (k,) bools, unwrap those columns.
        qd: optional measured velocities (N, k); NaN columns are derived from q instead.
    Returns:
        dict with ``t, q, qd, qdd, effort`` on the conditioned uniform grid (borders dropped,
        decimated), and ``fs``, ``cutoff_hz`` (the band of the conditioned data: the parallel
        filter's when there is one), ``derivative_cutoff_hz`` (the positions' filter),
        ``parallel_hz`` (None without a parallel filter), ``qd_smooth``, ``qdd_smooth`` (velocity
        and acceleration in the band of the effort: low-passed by the parallel filter when there
        is one, else ``qd``, ``qdd``), ``resampled``.
    Raises:
        CablelabError: too few samples or non-finite data.
    """
    t = np.asarray(t, dtype=float)
    q = np.asarray(q, dtype=float)
    effort = np.asarray(effort, dtype=float)
    n0 = t.shape[0]
    need = 2 * opts.border + 10
    if n0 < need:
        raise CablelabError(f"{source}: only {n0} samples, need at least {need} "
                            f"(2 x border {opts.border} + 10)")
    from .datachecks import check_raw_series

    check_raw_series(t, source, position=q, effort=effort)
    sig = [q, effort] + ([qd] if qd is not None else [])
    resampled = not is_uniform(t, opts.max_jitter)
    if resampled or any(not np.all(np.isfinite(s)) for s in sig):
        t, sig = uniform_grid(t, *sig)
        q, effort = sig[0], sig[1]
        qd = sig[2] if qd is not None else None
    for name, s in (("position", q), ("effort", effort)):
        if not np.all(np.isfinite(s)):
            raise CablelabError(f"{source}: {name} has no finite samples in some column")
    fs = 1.0 / float(np.median(np.diff(t)))
    if opts.cutoff_hz is not None:
        from .filters import check_cutoff

        check_cutoff(float(opts.cutoff_hz), fs, len(t))
    cutoff = default_cutoff(fs, opts)
    warnings: list[str] = []
    method = "central"
    if opts.cutoff_hz is None:  # a slow recording: fs / 10 must not filter the motion out
        default = cutoff
        cutoff, w = motion_cutoff(q, fs, cutoff, opts.order, source)
        warnings += w
        method = "spline" if cutoff > default else method   # central differences are biased there
    parallel = None
    if opts.cutoff_hz is None:  # quantized encoder: lower the cut-off until qdd is not noise
        from .velocity import (CUTOFF_OVER_EXCITATION, PARALLEL_OVER_EXCITATION,
                               excitation_bandwidth, quantization_aware_cutoff)

        low = quantization_aware_cutoff(q, fs, cutoff, opts.order)
        f_exc = excitation_bandwidth(q, fs, cutoff, opts.order)
        # never far below the motion's own band (the filter would remove the excitation)
        low = max(low, min(CUTOFF_OVER_EXCITATION * f_exc, cutoff))
        if opts.parallel and opts.effort_cutoff_hz is None and low < min(
                cutoff, PARALLEL_OVER_EXCITATION * f_exc):
            parallel = low  # derivatives at the default, both sides of the fit filtered at low
        else:
            cutoff = low
    rev = np.broadcast_to(np.asarray(revolute, dtype=bool), q.shape[1:] if q.ndim > 1 else ())
    if opts.unwrap and np.any(rev):
        q = np.where(rev, unwrap_angle(q), q)
    qf, qd_pos, qdd_pos = derivatives(q, fs, cutoff, opts.order, method)
    if qd is not None and np.all(np.isfinite(qd)):
        qd_f = lowpass(qd, fs, cutoff, opts.order)
        # acceleration from the encoder (its noise is known, the velocity sensor's is not)
        qdd = qdd_pos if opts.cutoff_hz is None else np.gradient(qd_f, 1.0 / fs, axis=0)
        qd_out = qd_f
    else:
        qd_out, qdd = qd_pos, qdd_pos
    qd_smooth, qdd_smooth = qd_out, qdd
    if parallel:
        effort = lowpass(effort, fs, parallel, opts.order)
        qd_smooth, qdd_smooth = lowpass(qd_out, fs, parallel, opts.order), lowpass(qdd, fs, parallel, opts.order)
    elif opts.effort_cutoff_hz == "same":
        effort = lowpass(effort, fs, cutoff, opts.order)
    elif opts.effort_cutoff_hz:
        effort = lowpass(effort, fs, float(opts.effort_cutoff_hz), opts.order)
    sl = slice(opts.border, t.shape[0] - opts.border, max(1, int(opts.decimate)))
    return {"t": t[sl], "q": qf[sl], "qd": qd_out[sl], "qdd": qdd[sl], "effort": effort[sl],
            "fs": fs / max(1, int(opts.decimate)), "cutoff_hz": parallel or cutoff,
            "derivative_cutoff_hz": cutoff, "parallel_hz": parallel,
            "qd_smooth": qd_smooth[sl], "qdd_smooth": qdd_smooth[sl], "resampled": resampled,
            "warnings": warnings}
