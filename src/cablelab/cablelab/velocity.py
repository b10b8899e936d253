"""Velocities of drives that stop: the zero-speed zone and honest handling of rest samples.

Real drives spend much of a recording at rest, and their friction passes smoothly through zero
speed (a narrow tanh band, stiction while stopped). Near and at zero speed:

* the measured effort is not a function of the motion: a stopped drive holds any effort inside
  its stiction band (the controller's integral and position error decide it), and inside the
  smooth band the friction is somewhere between -F_c and +F_c;
* the sign of a low-pass-filtered, differentiated (quantized) encoder position is filter noise,
  so a ``sign(qd)`` Coulomb column is wrong exactly there. With 40 % of the time at rest this
  biases the fitted Coulomb level 30-45 % low and lets viscous friction absorb the rest.

The remedy here is to *exclude* those samples from every fit (the same samples for every
candidate model, so scores stay comparable): a sample is in the zero-speed zone of an actuator
when ``|v| < ZONE_FRACTION * p99(|v|)`` (the 99th-percentile speed of that actuator in the
record) or below the speed resolution of the encoder (quantum x fs, one count per sample
stretched over the filter's smoothing, :func:`speed_resolution`). Motion samples keep the sign
model of 001 eq. 15 / the EMPS reference (the smooth band is much narrower than the zone).
Documented in docs/workbench.md "Drives that stop".
"""
from __future__ import annotations

import numpy as np

#: zero-speed zone: |v| below this fraction of the actuator's 99th-percentile speed
ZONE_FRACTION = 0.03


def position_quantum(q: np.ndarray) -> float:
    """Encoder resolution of a raw position record (N,): the most common smallest non-zero step
    between consecutive samples (0 if the record is not quantized or not finite)."""
    q = np.asarray(q, dtype=float).reshape(-1)
    d = np.abs(np.diff(q[np.isfinite(q)]))
    d = d[d > 0]
    if d.size < 10:
        return 0.0
    d = d[d > 1e-9 * max(float(np.max(np.abs(q))), 1e-300)]  # float round-off is not a step
    if d.size < 10:
        return 0.0
    small = float(np.min(d))
    # quantized: the small steps are (near) integer multiples of one count, and the record
    # shows it (repeated samples, or several multiples); a clean ramp of equal steps does not
    ratio = d[d <= 20 * small] / small
    if not np.all(np.abs(ratio - np.round(ratio)) < 0.05):
        return 0.0
    dq = np.abs(np.diff(q[np.isfinite(q)]))
    repeats = np.mean(dq <= 1e-9 * max(float(np.max(np.abs(q))), 1e-300)) > 0.01
    return float(small) if repeats or np.unique(np.round(ratio)).size >= 2 else 0.0


def speed_resolution(quantum: float, cutoff_hz: float) -> float:
    """Speed resolution of a filtered, differentiated quantized position: one count over the
    filter's time scale 1 / (2 pi f_c), in (unit of q)/s."""
    return float(quantum) * 2.0 * np.pi * float(cutoff_hz) if quantum > 0 and cutoff_hz else 0.0


def zero_speed_zone(act_vel: np.ndarray, floor: np.ndarray | float = 0.0,
                    fraction: float = ZONE_FRACTION) -> np.ndarray:
    """(n_act,) zone half-width per actuator: ``max(fraction * p99(|v|), floor)``."""
    v = np.abs(np.asarray(act_vel, dtype=float))
    v = v.reshape(v.shape[0], -1)
    p99 = np.nanpercentile(v, 99, axis=0)
    return np.maximum(fraction * p99, np.broadcast_to(np.asarray(floor, float), p99.shape))


def moving_mask(act_vel: np.ndarray, zone: np.ndarray) -> np.ndarray:
    """(N,) True where every actuator is outside its zero-speed zone."""
    v = np.abs(np.asarray(act_vel, dtype=float)).reshape(len(act_vel), -1)
    return np.all(v >= zone[None, :], axis=1)


def exclude_zero_speed(ds, floor: np.ndarray | float = 0.0, fraction: float = ZONE_FRACTION):
    """The dataset with samples in any actuator's zero-speed zone marked invalid (not fitted,
    not scored); the zone and the excluded share are kept in ``ds.signals`` (``zero_speed_zone``,
    ``rest_share``) for reports. Datasets without actuator velocities are returned unchanged.
    The speeds tested are ``ds.signals["rest_velocity"]`` when the dataset keeps one (the
    velocity in the band of the effort), else ``ds.act_vel``; on a parallel-filtered dataset the
    samples next to a rest are left out too (:func:`cablelab.parallel_filter.rest_guard`).
    Applied by the axis dataset and, for every other plant with joint or winch actuators, by
    :func:`cablelab.workbench.load_checked`."""
    if ds.act_vel is None or ds.n < 3:
        return ds
    # the velocity in the band of the effort when the dataset keeps one (parallel filtering:
    # act_vel is the lightly filtered velocity of the regressor, noisier near zero)
    v = ds.signals.get("rest_velocity", ds.act_vel)
    zone = zero_speed_zone(v, floor, fraction)
    moving = moving_mask(v, zone)
    if ds.parallel_hz:  # the parallel filter spreads the rests' model error: guard them
        from .parallel_filter import rest_guard

        moving = rest_guard(moving, ds.fs, ds.parallel_hz)
    return ds.replace(valid=ds.valid & moving,
                      signals={**ds.signals, "zero_speed_zone": zone,
                               "rest_share": float(1.0 - moving.mean())})


#: quantization noise allowed in the filtered acceleration, as a fraction of its RMS
QDD_NOISE_FRACTION = 0.005
#: lowest cut-off the quantization-aware choice goes down to, Hz
MIN_CUTOFF_HZ = 2.0


def white_position_noise(q: np.ndarray) -> float:
    """Std of white noise on a position record (N,) (e.g. stamp jitter resampled onto a grid), from
    its second difference d2: white noise of std s gives std(d2) = sqrt(6) s and a lag-1
    autocorrelation of -2/3, a smooth motion a correlation near +1. Returns 0 unless d2 looks
    like noise (correlation < -0.3)."""
    d2 = np.diff(np.asarray(q, dtype=float).reshape(-1), 2)
    d2 = d2[np.isfinite(d2)]
    if d2.size < 20 or not np.any(d2):
        return 0.0
    d2 = d2 - d2.mean()
    rho = float(np.sum(d2[1:] * d2[:-1]) / np.sum(d2 * d2))
    return float(np.std(d2) / np.sqrt(6.0)) if rho < -0.3 else 0.0


def quantization_qdd_noise(quantum: float, fs: float, cutoff_hz: float) -> float:
    """RMS of the acceleration noise that encoder quantization leaves after an ideal low-pass at
    ``cutoff_hz`` and two differentiations: white quantization noise of variance quantum^2 / 12
    over [0, fs/2], times |2 pi f|^4 integrated to f_c:
    ``sigma = quantum / sqrt(12) (2 pi)^2 sqrt(2 f_c^5 / (5 fs))`` (unit of q / s^2)."""
    return float(quantum / np.sqrt(12.0) * (2 * np.pi) ** 2 * np.sqrt(2.0 * cutoff_hz**5 / (5.0 * fs)))


def quantization_aware_cutoff(q: np.ndarray, fs: float, default_hz: float, order: int = 4) -> float:
    """Largest cut-off (``default_hz``, lowered step by step down to :data:`MIN_CUTOFF_HZ`) at
    which the quantization noise of the acceleration stays below
    :data:`QDD_NOISE_FRACTION` of the acceleration RMS, for every column of the raw position
    ``q`` (N,) or (N, k). White position noise (:func:`white_position_noise`) counts like
    quantization; clean, unquantized positions keep ``default_hz``."""
    from .filters import lowpass

    q = np.asarray(q, dtype=float).reshape(len(q), -1)
    cut = float(default_hz)
    for j in range(q.shape[1]):
        col = q[:, j]
        if not np.all(np.isfinite(col)):
            continue
        # white-equivalent count: quantization (uniform, quantum^2 / 12) or measured white noise
        quantum = max(position_quantum(col), np.sqrt(12.0) * white_position_noise(col))
        if quantum <= 0:
            continue
        # the acceleration's size, from a cut-off low enough that quantization cannot inflate it
        low = max(MIN_CUTOFF_HZ, min(cut, fs / 200.0))
        qdd = np.gradient(np.gradient(lowpass(col, fs, low, order), 1.0 / fs), 1.0 / fs)
        rms = float(np.sqrt(np.mean(qdd**2)))
        while cut > MIN_CUTOFF_HZ and quantization_qdd_noise(quantum, fs, cut) > QDD_NOISE_FRACTION * rms:
            cut = max(cut / 1.25, MIN_CUTOFF_HZ)
    return cut


#: share of the velocity's power below the excitation bandwidth
EXCITATION_POWER = 0.99
#: the cut-off is kept at least this multiple of the excitation bandwidth (when the default allows)
CUTOFF_OVER_EXCITATION = 2.0
#: parallel filtering when the cut-off is below this multiple of the excitation bandwidth (a
#: 4th-order zero-phase Butterworth attenuates f_c / 4 by 6e-5 %, f_c / 2 by 0.4 %)
PARALLEL_OVER_EXCITATION = 4.0


def excitation_bandwidth(q: np.ndarray, fs: float, cutoff_hz: float, order: int = 4) -> float:
    """Highest significant frequency of the motion, Hz: the frequency below which
    :data:`EXCITATION_POWER` of the power of the velocity (positions low-passed at ``cutoff_hz``
    and differentiated; every column of (N,) or (N, k) pooled) lies. Quantization noise carries
    a negligible share of the velocity's power, so the estimate needs no reference signal."""
    from .filters import lowpass

    q = np.asarray(q, dtype=float).reshape(len(q), -1)
    q = q[:, np.all(np.isfinite(q), axis=0)]
    if q.shape[1] == 0 or q.shape[0] < 16:
        return 0.0
    v = np.gradient(lowpass(q, fs, cutoff_hz, order), 1.0 / fs, axis=0)
    v = v - v.mean(axis=0)
    p = (np.abs(np.fft.rfft(v, axis=0)) ** 2).sum(axis=1)
    f = np.fft.rfftfreq(v.shape[0], 1.0 / fs)
    c = np.cumsum(p)
    if c[-1] <= 0:
        return 0.0
    return float(f[np.searchsorted(c, EXCITATION_POWER * c[-1])])


# ------------------------------------------------------------------- measured vs derived velocity

#: a measured velocity is trusted when, on the moving samples, it agrees with the derivative of
#: the position within this factor of scale (rad/s vs deg/s is 57, vs rpm 9.5, m/s vs mm/s 1000)
VELOCITY_SCALE_TOLERANCE = 1.5
#: ... and correlates with it at least this much (a sign flip gives -1, an unrelated signal ~0)
VELOCITY_MIN_CORRELATION = 0.7


def velocity_agreement(t, q, qd) -> dict | None:
    """How a measured velocity agrees with the derivative of its position, on the moving samples.

    Both are low-passed alike (zero-phase, at fs / 10 but never below the encoder's speed
    resolution band); the derivative is a central difference over the stamps. Moving samples:
    derived speed above a quarter of its 99th percentile and above the speed resolution of the
    encoder (:func:`speed_resolution`: a quantized position's derivative is noise below it).

    Args:
        t: (N,) s; q: (N,) position; qd: (N,) measured velocity (unit of q / s).
    Returns:
        ``{"scale", "correlation", "samples"}`` (scale: median of measured / derived on the moving
        samples, signed), or None when the record is too short or does not move.
    """
    from .filters import lowpass

    t, q, qd = (np.asarray(a, dtype=float).reshape(-1) for a in (t, q, qd))
    ok = np.isfinite(t) & np.isfinite(q) & np.isfinite(qd)
    t, q, qd = t[ok], q[ok], qd[ok]
    if t.size < 50:
        return None
    keep = np.concatenate([[True], np.diff(t) > 0])
    t, q, qd = t[keep], q[keep], qd[keep]
    if t.size < 50 or not np.all(np.diff(t) > 0):
        return None
    fs = 1.0 / float(np.median(np.diff(t)))
    cut = fs / 10.0
    vd = np.gradient(lowpass(q, fs, cut), t)
    vm = lowpass(qd, fs, cut)
    speed = np.abs(vd)
    p99 = float(np.percentile(speed, 99))
    floor = max(0.25 * p99, speed_resolution(position_quantum(q), cut))
    moving = speed > floor
    if p99 <= 0 or moving.sum() < 20:
        return None
    a, b = vm[moving], vd[moving]
    sa, sb = np.std(a), np.std(b)
    corr = float(np.corrcoef(a, b)[0, 1]) if sa > 0 and sb > 0 else 0.0
    return {"scale": float(np.median(a / b)), "correlation": corr, "samples": int(moving.sum())}


def velocity_contradiction(agreement: dict | None) -> str:
    """What is wrong with a measured velocity given :func:`velocity_agreement` (``""``: nothing)."""
    if agreement is None:
        return ""
    s, r = agreement["scale"], agreement["correlation"]
    units = not 1.0 / VELOCITY_SCALE_TOLERANCE <= abs(s) <= VELOCITY_SCALE_TOLERANCE
    if s < 0 or r <= -VELOCITY_MIN_CORRELATION:
        return "sign flipped" + (f", and {abs(s):.3g}x its size, units?" if units else "")
    if r < VELOCITY_MIN_CORRELATION:
        return "not correlated with the derivative of position"
    if units:
        return f"{s:.3g}x the derivative of the position, units?"
    return ""
