"""Sensor models and the case interface shared by the diagnosis-benchmark generators
(bench/diagnosis_cases.py for the axis, bench/cases_{crane,cdpr,leg,suspended}.py).

None of this uses the fitting code: it turns a simulated truth into what a machine records
(coloured noise with outliers, encoder quantization, minimum-jerk moves) and describes what the
benchmark checks for a case (:class:`PlantCase`).
"""
from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np
import scipy.signal


def coloured_noise(rng, n: int, sigma: float, ar: float = 0.0, outlier_rate: float = 0.0) -> np.ndarray:
    """(n,) AR(1) noise of standard deviation ``sigma`` (coefficient ``ar``) plus sparse
    +-10 sigma outliers (a share ``outlier_rate`` of the samples)."""
    e = rng.standard_normal(n) * sigma * np.sqrt(1 - ar**2)
    noise = scipy.signal.lfilter([1.0], [1.0, -ar], e)
    spikes = rng.random(n) < outlier_rate
    noise[spikes] += rng.choice([-1, 1], spikes.sum()) * 10 * sigma
    return noise


def quantize(x: np.ndarray, quantum: float) -> np.ndarray:
    """Encoder reading of ``x`` with resolution ``quantum`` (0: exact)."""
    return np.round(x / quantum) * quantum if quantum > 0 else np.asarray(x, float)


def min_jerk(s):
    """Minimum-jerk shape on s in [0, 1] (clipped): (x, dx/ds, d2x/ds2)."""
    s = np.clip(s, 0.0, 1.0)
    return 10 * s**3 - 15 * s**4 + 6 * s**5, (30 * s**2 - 60 * s**3 + 30 * s**4), (60 * s - 180 * s**2 + 120 * s**3)


def moves_and_rests(rng, start, limits, duration: float, rest_fraction: float, profile: str,
                    move_time: float, chirp_amp, chirp_f0=(0.05, 0.1), chirp_f1=(0.25, 0.35), dt: float = 1e-3):
    """A multi-axis reference of moves separated by rests, tabulated: ``fn(t) -> (q, qd, qdd)``
    (N, k) each, and the end time of the last move.

    ``profile`` "ptp": minimum-jerk point-to-point moves of all axes together to random targets in
    ``limits`` ((lo, hi) per axis), each ``move_time`` s (several speed levels follow from the
    random distances); "chirp": a glide to a random centre, then a windowed linear chirp
    ``q0 + amp w(s) sin(2 pi (f0 tau + k tau^2 / 2))`` (f0, f1 drawn from the given ranges,
    amplitude ``chirp_amp`` x U(0.4, 1) per axis) that returns to the centre. Rests fill
    ``rest_fraction`` of ``duration`` (before, between and after the moves)."""
    start = np.asarray(start, float)
    k_ax = start.size
    rest = rest_fraction * duration
    per = move_time if profile == "ptp" else 2 * move_time
    n_moves = max(2, int((duration - rest) / per))
    move_d = (duration - rest) / n_moves / (1 if profile == "ptp" else 2)
    rest_d = rest / (n_moves + 1)
    q = start.copy()
    segs, t = [], rest_d
    for _ in range(n_moves):
        if profile == "ptp":
            target = np.array([rng.uniform(*lim) for lim in limits])
            segs.append((t, t + move_d, "ptp", (q.copy(), target - q)))
            q = target
        else:
            amp = np.asarray(chirp_amp, float) * rng.uniform(0.4, 1.0, k_ax)
            centre = np.array([rng.uniform(lo + a, hi - a) for (lo, hi), a in zip(limits, amp)])
            segs.append((t, t + move_d, "ptp", (q.copy(), centre - q)))
            q = centre
            segs.append((t + move_d, t + 2 * move_d, "chirp", (q.copy(), amp, rng.uniform(*chirp_f0),
                                                               rng.uniform(*chirp_f1))))
            t += move_d
        t += move_d + rest_d
    grid = np.arange(-0.5, t + 1.0, dt)
    Q, V, A = np.tile(start, (grid.size, 1)), np.zeros((grid.size, k_ax)), np.zeros((grid.size, k_ax))
    for a, b, kind, p in segs:
        d = b - a
        inside, after = (grid >= a) & (grid < b), grid >= b
        s = (grid[inside] - a) / d
        if kind == "ptp":
            q0, dq = p
            x, xd, xdd = min_jerk(s)
            Q[inside] = q0 + dq * x[:, None]
            V[inside], A[inside] = dq * xd[:, None] / d, dq * xdd[:, None] / d**2
            Q[after] = q0 + dq
        else:
            q0, amp, f0, f1 = p
            kk = (f1 - f0) / d
            tau = grid[inside] - a
            w, wd, wdd = min_jerk(np.minimum(s, 1 - s) * 2)
            sg = np.where(s < 0.5, 2.0 / d, -2.0 / d)
            ph = 2 * np.pi * (f0 * tau + 0.5 * kk * tau**2)
            om = 2 * np.pi * (f0 + kk * tau)
            sn, cs = np.sin(ph), np.cos(ph)
            Q[inside] = q0 + amp * (w * sn)[:, None]
            V[inside] = amp * (wd * sg * sn + w * om * cs)[:, None]
            A[inside] = amp * (wdd * sg**2 * sn + 2 * wd * sg * om * cs
                               + w * (2 * np.pi * kk * cs - om**2 * sn))[:, None]
            Q[after] = q0

    def r(tt):
        tt = np.atleast_1d(np.asarray(tt, float))
        return tuple(np.stack([np.interp(tt, grid, X[:, i]) for i in range(k_ax)], 1) for X in (Q, V, A))

    return r, float(t)


def slow_sines(limits, amp, hz, phase):
    """Reference ``fn(t) -> (x, xd, xdd)``: a sine per axis (or drive) about the centre of
    ``limits`` ((lo, hi) per axis), amplitudes ``amp``, frequencies ``hz`` (Hz), phases (rad).
    The simulators start at the reference's first point, at rest; the speed there is small,
    which their PD loops take up."""
    centre = np.array([0.5 * (lo + hi) for lo, hi in limits])
    w = 2 * np.pi * np.asarray(hz, float)
    amp, phase = np.asarray(amp, float), np.asarray(phase, float)

    def fn(t):
        arg = w * np.atleast_1d(np.asarray(t, float))[:, None] + phase
        return centre + amp * np.sin(arg), amp * w * np.cos(arg), -amp * w * w * np.sin(arg)

    return fn


def draw_slow_sines(rng, limits):
    """:func:`slow_sines` drawn for a slow first recording: 0.015-0.035 Hz, amplitudes 30-60 % of
    each axis's half range, random phases."""
    n = len(limits)
    hz = rng.uniform(0.015, 0.035, n)
    amp = rng.uniform(0.3, 0.6, n) * 0.5 * np.array([hi - lo for lo, hi in limits])
    phase = rng.uniform(0, 2 * np.pi, n)
    return slow_sines(limits, amp, hz, phase)


def rel_param_error(fitted: dict, true: dict) -> float:
    """|p_fit - p_true| / |p_true| over the parameter vector of one effect (Euclidean norms;
    a parameter missing from the fit counts as infinite error)."""
    if any(k not in fitted for k in true):
        return float("inf")
    a = np.array([fitted[k] for k in true], float)
    b = np.array([true[k] for k in true], float)
    return float(np.linalg.norm(a - b) / np.linalg.norm(b))


@dataclass
class PlantCase:
    """What the benchmark needs of a generated case of any plant.

    Attributes:
        plant: plant name. seed: case seed. family: a short label for the per-family table.
        fs: recording rate, Hz. hidden: the hidden effect ids (empty = control case).
        effects: effects added to the plant's nominal model (``cablelab diagnose --effects``):
            the truth contains them, the nominal model knows them.
        fixed: known parameters (``--fix``). options: dataset options (``--tensions`` ...).
        true_params: effect id -> {fitted parameter name: true value}; an effect without an
            entry is checked for detection only (parameters not identifiable from the record).
        description: the plant description YAML written into the bag.
        truth: free-form truth values (for the failure printout).
    """

    plant: str
    seed: int
    family: str
    fs: float
    hidden: tuple
    description: str
    effects: tuple = ()
    fixed: dict = field(default_factory=dict)
    options: dict = field(default_factory=dict)
    true_params: dict = field(default_factory=dict)
    truth: dict = field(default_factory=dict)
    velocity_recorded: bool = False

    def label(self) -> str:
        return " + ".join(self.hidden) or "control"
