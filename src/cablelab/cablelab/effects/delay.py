"""Constant delay between actuation and measurement (any plant); a nonlinear parameter.

Convention: the effort the model computes from the motion at time t appears in the measurement
at t + tau, i.e. ``y_meas(t) = y_model(t - tau)``. The effect compares ``y_meas(t + tau)`` (linear
interpolation) with ``y_model(t)``; samples whose shifted time leaves the record or falls in a gap
of the time axis are marked invalid. tau < 0 means the measurement leads the motion (typical when
the "effort" is a controller command). tau is found by a bounded outer search around the linear
least squares (separable least squares, see :mod:`cablelab.fit.identify`).
"""
from __future__ import annotations

from typing import Mapping

import numpy as np

from ..model import Dataset, Effect, Param
from . import register

#: search range of tau, s
DELAY_BOUNDS = (-0.05, 0.05)


def shift_time(t: np.ndarray, y: np.ndarray, tau: float) -> tuple[np.ndarray, np.ndarray]:
    """``y(t + tau)`` by linear interpolation, and the mask where it is defined.

    Args:
        t: (N,) increasing times, s (gaps allowed: more than 1.5 median periods).
        y: (N, C) samples.
        tau: shift, s.
    Returns:
        (y_shift (N, C), ok (N,) bool).
    """
    n = t.shape[0]
    ts = t + tau
    i = np.clip(np.searchsorted(t, ts, side="right") - 1, 0, n - 2)
    t0, t1 = t[i], t[i + 1]
    w = (ts - t0) / np.where(t1 > t0, t1 - t0, 1.0)
    ys = y[i] * (1.0 - w)[:, None] + y[i + 1] * w[:, None]
    dt = np.median(np.diff(t)) if n > 1 else 1.0
    ok = (ts >= t[0]) & (ts <= t[-1]) & ((t1 - t0) <= 1.5 * dt)
    # the shift must not jump over a gap between t and t + tau either
    # (with no gap the index distance matches the time shift)
    k = np.arange(n)
    ok &= np.abs(i - k) * dt >= abs(tau) - 2.0 * dt
    return ys, ok


def _transform(ds: Dataset, values: Mapping[str, float]) -> Dataset:
    tau = float(values.get("tau", 0.0))
    if tau == 0.0:
        return ds
    ys, ok = shift_time(ds.t, ds.y, tau)
    return ds.replace(y=ys, valid=ds.valid & ok)


TIME_DELAY = register(Effect(
    id="time_delay",
    plants=("*",),
    params=(),
    explanation="the measured effort is delayed (or leads) the motion by a constant time",
    signature="residual correlates with the derivative of the effort (phase lag)",
    reference="mujoco.sysid signal_modifier.apply_delay; 003 sec. 4 (sensor timing)",
    nonlinear=(Param("tau", "s", 0.0, DELAY_BOUNDS[0], DELAY_BOUNDS[1], "measurement delay"),),
    transform=_transform,
))
