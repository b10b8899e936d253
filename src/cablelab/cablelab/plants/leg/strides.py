"""Sampled hopping records cut into phases and strides (003 sec. 3.3-3.4: flight segments, stance
segments, apex-to-apex single strides), and apexes located by quadratic interpolation.

All functions are vectorised over the samples of one record: ``t`` (N,) s, ``z`` (N,) m,
``phase`` (N,) 0 flight / 1 stance (contact switch or estimated).
"""
from __future__ import annotations

import numpy as np


def phase_runs(phase: np.ndarray) -> list[tuple[int, int, int]]:
    """Maximal runs of equal phase: ``(start, stop, phase)`` with ``stop`` exclusive."""
    ph = np.asarray(phase).astype(int)
    if ph.size == 0:
        return []
    edges = np.flatnonzero(np.diff(ph)) + 1
    starts = np.concatenate([[0], edges])
    stops = np.concatenate([edges, [ph.size]])
    return [(int(a), int(b), int(ph[a])) for a, b in zip(starts, stops)]


def parabola_peak(t3: np.ndarray, z3: np.ndarray) -> tuple[float, float]:
    """(t, z) of the vertex of the parabola through three samples (uniform or not)."""
    (t0, t1, t2), (z0, z1, z2) = t3, z3
    den = (t0 - t1) * (t0 - t2) * (t1 - t2)
    a = (t2 * (z1 - z0) + t1 * (z0 - z2) + t0 * (z2 - z1)) / den
    b = (t2 * t2 * (z0 - z1) + t1 * t1 * (z2 - z0) + t0 * t0 * (z1 - z2)) / den
    if a >= 0:  # not a maximum: keep the middle sample
        return float(t1), float(z1)
    c = z1 - a * t1 * t1 - b * t1
    tv = -b / (2 * a)
    return float(tv), float(a * tv * tv + b * tv + c)


def apexes(t: np.ndarray, z: np.ndarray, phase: np.ndarray) -> np.ndarray:
    """(K, 2) apex (time s, height m) of every complete flight run: the highest sample of the run
    refined by the parabola through it and its two neighbours. Runs touching the record ends or
    whose highest sample is at a run end (no apex inside) are skipped."""
    out = []
    for a, b, ph in phase_runs(phase):
        if ph != 0 or a == 0 or b >= len(z) or b - a < 3:
            continue
        i = a + int(np.argmax(z[a:b]))
        if i == a or i == b - 1:
            continue
        out.append(parabola_peak(t[i - 1:i + 2], z[i - 1:i + 2]))
    return np.array(out).reshape(-1, 2)


def apex_indices(t: np.ndarray, apex_times: np.ndarray) -> np.ndarray:
    """Sample index nearest each apex time."""
    return np.clip(np.searchsorted(t, apex_times), 0, len(t) - 1)


def segments(phase: np.ndarray, which: int, margin: int = 0) -> list[tuple[int, int]]:
    """Index ranges ``(start, stop)`` of complete runs of phase ``which`` (0 flight, 1 stance),
    shrunk by ``margin`` samples at both ends (avoids the samples at the impacts)."""
    out = []
    n = len(phase)
    for a, b, ph in phase_runs(phase):
        if ph == which and a > 0 and b < n and b - a > 2 * margin + 3:
            out.append((a + margin, b - margin))
    return out


def strides(t: np.ndarray, z: np.ndarray, phase: np.ndarray) -> list[tuple[int, int]]:
    """Apex-to-apex single strides as sample ranges ``(start, stop)`` (start at the sample nearest
    one apex, stop at the sample nearest the next, inclusive end excluded)."""
    ap = apexes(t, z, phase)
    idx = apex_indices(t, ap[:, 0])
    return [(int(a), int(b) + 1) for a, b in zip(idx[:-1], idx[1:]) if b > a]
