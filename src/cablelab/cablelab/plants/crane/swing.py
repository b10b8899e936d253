"""Swing angles and rope length from motion capture, offline (vectorised) and live (002 sec. 5.1.3, 6.3).

Offline: :func:`estimate_swing` takes the motion-capture positions of the boom tip and the payload
(N, 3) with their stamps and the slew angle (from ``/crane/joint_states``, its own stamps), and
returns :class:`~cablelab.plants.crane.kinematics.SwingAngles` plus a :class:`SwingReport` of
what the data conditioning met (002 sec. 5.1.3): NaN dropouts (interpolated, flagged invalid),
frozen / non-increasing stamps (dropped), irregular sample periods (derivatives taken on the true
times, ``numpy.gradient`` on a non-uniform grid), angle wrap-around (unwrapped, never the
"more than 300 degrees" rule of 002 but ``numpy.unwrap``).

Live: :class:`SwingTracker` does the same one sample at a time for the estimator node.
"""
from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

from ...errors import CablelabError
from .kinematics import SwingAngles, slewing_offset, swing_from_offset

__all__ = ["SwingReport", "estimate_swing", "SwingTracker", "IRREGULAR_FRACTION"]

#: a sample period deviating from the median by more than this fraction counts as irregular
IRREGULAR_FRACTION = 0.5


@dataclass
class SwingReport:
    """What the conditioning found (counts of samples). ``as_dict()`` for JSON / diagnostics."""

    samples: int = 0
    dropouts: int = 0
    frozen_stamps: int = 0
    irregular_periods: int = 0
    slew_wraps: int = 0
    swing_wraps: int = 0
    median_period: float = float("nan")

    def as_dict(self) -> dict:
        return {k: (float(v) if isinstance(v, float) else int(v)) for k, v in vars(self).items()}

    def problems(self) -> list[str]:
        """One short phrase per problem found (empty when the data were clean)."""
        out = []
        if self.dropouts:
            out.append(f"{self.dropouts} motion-capture dropouts (NaN poses) interpolated")
        if self.frozen_stamps:
            out.append(f"{self.frozen_stamps} frozen/non-increasing stamps dropped")
        if self.irregular_periods:
            out.append(f"{self.irregular_periods} irregular sample periods")
        if self.slew_wraps or self.swing_wraps:
            out.append(f"{self.slew_wraps + self.swing_wraps} angle wrap-arounds unwrapped")
        return out


def _increasing(t: np.ndarray) -> np.ndarray:
    """Mask keeping samples whose stamp is later than every earlier kept stamp."""
    run_max = np.maximum.accumulate(t)
    keep = np.ones(t.shape, dtype=bool)
    keep[1:] = t[1:] > run_max[:-1]
    return keep


def _count_wraps(x: np.ndarray) -> int:
    d = np.diff(x[np.isfinite(x)])
    return int(np.sum(np.abs(d) > np.pi))


def estimate_swing(t, tip, payload, t_slew, slew, *, cutoff_hz: float | None = None,
                   order: int = 2, source: str = "data") -> tuple[SwingAngles, SwingReport]:
    """Swing angles, rope length and their rates from motion capture (CONTRACT sec. 2).

    Args:
        t: (N,) motion-capture stamps, s. tip, payload: (N, 3) pivot positions in ``world``, m
            (NaN rows = dropouts).
        t_slew, slew: (M,) stamps and slew angle alpha, rad (interpolated at ``t``; unwrapped).
        cutoff_hz: optional zero-phase Butterworth low-pass of the angles before differentiation
            (None = no filter: derivatives of the raw angles).
        order: Butterworth order.
        source: name for error messages.
    Returns:
        ``(SwingAngles, SwingReport)``; samples with frozen stamps are removed from the output.
    Raises:
        CablelabError: fewer than 2 usable samples, shape mismatch.
    """
    t = np.asarray(t, dtype=float).reshape(-1)
    tip = np.asarray(tip, dtype=float).reshape(-1, 3)
    payload = np.asarray(payload, dtype=float).reshape(-1, 3)
    if not (t.shape[0] == tip.shape[0] == payload.shape[0]):
        raise CablelabError(f"{source}: {t.shape[0]} stamps, {tip.shape[0]} tip and "
                            f"{payload.shape[0]} payload poses")
    t_slew = np.asarray(t_slew, dtype=float).reshape(-1)
    slew = np.asarray(slew, dtype=float).reshape(-1)
    rep = SwingReport(samples=int(t.shape[0]))
    keep = _increasing(t)
    rep.frozen_stamps = int((~keep).sum())
    t, tip, payload = t[keep], tip[keep], payload[keep]
    ok_s = np.isfinite(slew) & np.isfinite(t_slew)
    ks = _increasing(np.where(ok_s, t_slew, -np.inf)) & ok_s
    if ks.sum() < 2:
        raise CablelabError(f"{source}: fewer than 2 usable slew-angle samples")
    rep.slew_wraps = _count_wraps(slew[ks])
    alpha = np.interp(t, t_slew[ks], np.unwrap(slew[ks]))
    ok = np.isfinite(tip).all(1) & np.isfinite(payload).all(1)
    rep.dropouts = int((~ok).sum())
    if ok.sum() < 2:
        raise CablelabError(f"{source}: fewer than 2 motion-capture samples with finite poses")
    dt = np.diff(t)
    if dt.size:
        med = float(np.median(dt))
        rep.median_period = med
        rep.irregular_periods = int(np.sum(np.abs(dt - med) > IRREGULAR_FRACTION * med))
    th1, th2, d = swing_from_offset(slewing_offset(tip[ok], payload[ok], alpha[ok]))
    rep.swing_wraps = _count_wraps(th1)
    th1 = np.unwrap(th1)
    if rep.dropouts:
        tk = t[ok]
        th1, th2, d = (np.interp(t, tk, x) for x in (th1, th2, d))
    x = np.stack([th1, th2, d], axis=1)
    if cutoff_hz:
        from ...conditioning import lowpass

        x = lowpass(x, 1.0 / rep.median_period, cutoff_hz, order)
    xd = np.gradient(x, t, axis=0) if t.shape[0] > 1 else np.zeros_like(x)
    sw = SwingAngles(t=t, theta1=x[:, 0], theta2=x[:, 1], rope_length=x[:, 2],
                     theta1_dot=xd[:, 0], theta2_dot=xd[:, 1], rope_length_dot=xd[:, 2], valid=ok)
    return sw, rep


@dataclass
class SwingTracker:
    """Live swing estimate, one motion-capture sample at a time (the estimator node's core).

    Velocities are first differences of the (unwrapped) angles smoothed by a first-order low-pass
    of time constant ``tau`` (s; 0 = raw differences).

    Attributes:
        tau: velocity smoothing time constant, s.
        stale_after: a sample older than this relative to the previous one is not differenced, s.
    """

    tau: float = 0.02
    stale_after: float = 0.5
    last_t: float | None = None
    last_x: np.ndarray | None = None
    last_v: np.ndarray = field(default_factory=lambda: np.zeros(3))
    counts: dict = field(default_factory=lambda: {"ok": 0, "dropout": 0, "frozen": 0, "gap": 0,
                                                  "irregular": 0})
    period: float | None = None  # running estimate of the sample period, s

    def update(self, t: float, tip, payload, slew: float) -> tuple[str, np.ndarray | None, np.ndarray | None]:
        """Feed one sample. Returns ``(status, [theta1, theta2, d], [rates])``.

        Irregular sample periods (off the running period by more than ``IRREGULAR_FRACTION``)
        are counted in ``counts["irregular"]``; the rate always uses the true time difference.
        status is ``"ok"``, ``"dropout"`` (non-finite pose or slew: nothing estimated),
        ``"frozen"`` (stamp not after the last one: ignored) or ``"gap"`` (estimated, but the
        velocity restarted because the previous sample is older than ``stale_after``).
        """
        tip = np.asarray(tip, dtype=float).reshape(3)
        payload = np.asarray(payload, dtype=float).reshape(3)
        if not (np.isfinite(tip).all() and np.isfinite(payload).all() and np.isfinite(slew)
                and np.isfinite(t)):
            self.counts["dropout"] += 1
            return "dropout", None, None
        if self.last_t is not None and t <= self.last_t:
            self.counts["frozen"] += 1
            return "frozen", None, None
        th1, th2, d = swing_from_offset(slewing_offset(tip[None], payload[None], np.array([slew])))
        x = np.array([th1[0], th2[0], d[0]])
        status = "ok"
        if self.last_x is None or t - self.last_t > self.stale_after:
            v = np.zeros(3)
            status = "gap" if self.last_x is not None else "ok"
        else:
            x[0] = self.last_x[0] + np.angle(np.exp(1j * (x[0] - self.last_x[0])))  # unwrap theta1
            dt = t - self.last_t
            if self.period is None:
                self.period = dt
            elif abs(dt - self.period) > IRREGULAR_FRACTION * self.period:
                self.counts["irregular"] += 1   # irregular period: the difference uses the true dt
            else:
                self.period += 0.05 * (dt - self.period)
            raw = (x - self.last_x) / dt
            a = dt / (self.tau + dt) if self.tau > 0 else 1.0
            v = self.last_v + a * (raw - self.last_v)
        self.counts[status] += 1
        self.last_t, self.last_x, self.last_v = float(t), x, v
        return status, x, v
