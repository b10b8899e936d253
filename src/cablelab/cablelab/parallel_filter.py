"""Parallel filtering of the identification equations (IDIM-LS, Gautier; EMPS reference).

The inverse model is linear in the parameters sample by sample, ``y_i = phi_i theta + e_i``.
Any linear operator ``L`` along time applied to BOTH sides keeps it exact:
``L y = (L Phi) theta + L e``. The parallel filter is such an ``L``: the same zero-phase
Butterworth low-pass (``scipy.signal.sosfiltfilt``) applied to the measured output and to every
regressor column, whatever the column is (an acceleration, ``sign(qd)``, ``sin(q)``, a column
mapped through a pose-dependent matrix).

Why: a quantized encoder forces a low cut-off for the acceleration (a few Hz for a
slow 100 Hz slew axis). When only the positions are filtered, the inertia column is attenuated
where the effort is not, and the Coulomb column ``sign(H qd)`` is a sharp step where the
measured friction is smoothed by nothing; under 1-3 Hz chirps the least squares then moves
10-40 % of the Coulomb level into viscous friction. With the parallel filter the derivatives are
taken at a light cut-off (the default fs / 10) and the quantization-aware cut-off becomes the
parallel filter of both sides, so the attenuation cancels.

A dataset declares its filter in :attr:`cablelab.dataset.Dataset.parallel_hz` (its ``y`` is
already filtered on the whole record); :meth:`cablelab.model.Model.regressor` filters every
column on the dataset's own samples. The two operators differ only within the filter's settling
time of a segment edge (record ends, cross-validation cuts, gaps), which
:func:`edge_mask` marks invalid.
"""
from __future__ import annotations

from functools import lru_cache

import numpy as np
import scipy.signal

#: Butterworth order of the parallel filter (applied forward and backward)
ORDER = 4
#: samples within SETTLE_PERIODS / cutoff of a segment edge are not used (filter settling)
SETTLE_PERIODS = 1.0
#: a time step above GAP_FACTOR x the median period starts a new segment
GAP_FACTOR = 1.5


def segments(t: np.ndarray) -> list[tuple[int, int]]:
    """Contiguous runs ``[(start, stop)]`` of a time axis (N,): a new run after every step longer
    than :data:`GAP_FACTOR` x the median period (a gap, or a cut between cross-validation
    blocks)."""
    t = np.asarray(t, dtype=float).reshape(-1)
    n = t.shape[0]
    if n < 2:
        return [(0, n)]
    dt = np.diff(t)
    cut = np.flatnonzero(dt > GAP_FACTOR * np.median(dt)) + 1
    bounds = np.concatenate([[0], cut, [n]])
    return [(int(a), int(b)) for a, b in zip(bounds[:-1], bounds[1:])]


def settle_samples(fs: float, cutoff_hz: float) -> int:
    """Samples of filter settling at a segment edge: :data:`SETTLE_PERIODS` / cutoff."""
    return int(np.ceil(SETTLE_PERIODS * fs / float(cutoff_hz)))


@lru_cache(maxsize=64)
def _butter(order: int, cutoff_hz: float, fs: float) -> np.ndarray:
    return scipy.signal.butter(order, cutoff_hz, fs=fs, output="sos")


def parallel_filter(x: np.ndarray, t: np.ndarray, cutoff_hz: float, order: int = ORDER) -> np.ndarray:
    """Zero-phase low-pass of an (N, ...) array along time, segment by segment (no filtering
    across a gap or a cross-validation cut). Non-finite entries are filtered as 0 (those samples
    are invalid in any fit). Segments too short for the filter are returned unfiltered (their
    samples fall inside :func:`edge_mask` anyway)."""
    x = np.asarray(x, dtype=float)
    t = np.asarray(t, dtype=float)
    n = x.shape[0]
    if n < 2:
        return x.copy()
    fs = 1.0 / float(np.median(np.diff(t)))
    if not 0 < cutoff_hz < fs / 2:
        return x.copy()
    sos = _butter(int(order), float(cutoff_hz), float(np.float32(fs)))
    x0 = np.where(np.isfinite(x), x, 0.0)
    out = x0.copy()
    pad_default = 3 * (2 * len(sos) + 1) * 3
    for a, b in segments(t):
        if b - a > 2 * pad_default:
            out[a:b] = scipy.signal.sosfiltfilt(sos, x0[a:b], axis=0, padlen=pad_default)
    return out


def edge_mask(t: np.ndarray, cutoff_hz: float) -> np.ndarray:
    """(N,) False within :func:`settle_samples` of each segment's ends (and for segments too
    short to have a settled middle), True elsewhere."""
    t = np.asarray(t, dtype=float).reshape(-1)
    n = t.shape[0]
    ok = np.ones(n, dtype=bool)
    if n < 2:
        return ok
    fs = 1.0 / float(np.median(np.diff(t)))
    k = settle_samples(fs, cutoff_hz)
    for a, b in segments(t):
        ok[a:min(a + k, b)] = False
        ok[max(b - k, a):b] = False
    return ok


#: samples within REST_GUARD_PERIODS / cutoff of a rest are not used (see :func:`rest_guard`)
REST_GUARD_PERIODS = 0.5


def rest_guard(moving: np.ndarray, fs: float, cutoff_hz: float,
               periods: float = REST_GUARD_PERIODS) -> np.ndarray:
    """(N,) ``moving`` with the samples near a rest removed as well. A rest is a run of
    not-moving samples longer than the guard ``k = periods x fs / cutoff``; the filter spreads the
    model error of a rest (a stopped or creeping drive holds an effort the friction law does not
    give) over about ``k`` samples either side. Short runs (velocity reversals in motion, where
    the friction law holds) keep their neighbours."""
    moving = np.asarray(moving, dtype=bool)
    n = moving.size
    k = int(round(periods * fs / float(cutoff_hz)))
    if k < 1 or n == 0:
        return moving
    still = ~moving
    edges = np.flatnonzero(np.diff(np.concatenate([[0], still.astype(int), [0]])))
    starts, stops = edges[::2], edges[1::2]
    out = moving.copy()
    for a, b in zip(starts, stops):
        if b - a > k:
            out[max(0, a - k):min(n, b + k)] = False
    return out
