"""Constant delay between actuation and measurement (any plant); a nonlinear parameter.

Convention: the effort the model computes from the motion at time t appears in the measurement
at t + tau, i.e. ``y_meas(t) = y_model(t - tau)``. The effect evaluates the model on the motion
signals shifted to ``t - tau`` (linear interpolation of every time-indexed signal, actuator
velocity and map; a signal is interpolated when first read, :class:`ShiftedSignals`); samples
whose shifted time leaves the record or crosses a gap of the time axis are marked invalid. The
measurement itself is never interpolated: interpolating a noisy signal at a fractional shift
averages neighbouring samples and would "explain" white noise as a delay.
When a plant's output channels are raw measurements mapped through a motion-dependent matrix
(the CDPR's wrench ``W(pose(t)) t_meas(t)``), shifting the motion alone would also shift that
map: the plant's ``remeasure`` hook (:class:`cablelab.registry.Plant`) then keeps the raw
measurement unshifted and re-forms ``y = W(pose(t - tau)) t_meas(t)``, the wrench the measured
tensions exert at the pose they belong to (the measured tensions are not interpolated either).
tau < 0 means the measurement leads the motion (typical when the "effort" is a controller
command). tau is found by a bounded outer search around the linear least squares (separable least
squares, see :mod:`cablelab.fit.identification`).
"""
from __future__ import annotations

from collections.abc import MutableMapping
from typing import Mapping

import numpy as np

from ..dataset import Dataset
from .base import Effect, Param
from . import register

#: search range of tau, s
DELAY_BOUNDS = (-0.05, 0.05)


def shift_weights(t: np.ndarray, tau: float) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Interpolation of samples at ``t - tau``: indices i, weights w (value = (1-w) x[i] + w x[i+1])
    and the mask where it is defined (inside the record, not across a gap)."""
    n = t.shape[0]
    ts = t - tau
    dt = float(np.min(np.diff(t))) if n > 1 else 1.0
    if abs((t[-1] - t[0]) - (n - 1) * dt) <= 1e-6 * dt * n:
        # uniform grid (the usual case after conditioning): no search needed
        i = np.clip(np.floor((ts - t[0]) / dt + 1e-9).astype(int), 0, n - 2)
    else:
        i = np.clip(np.searchsorted(t, ts, side="right") - 1, 0, n - 2)
    t0, t1 = t[i], t[i + 1]
    w = np.clip((ts - t0) / np.where(t1 > t0, t1 - t0, 1.0), 0.0, 1.0)
    ok = (ts >= t[0]) & (ts <= t[-1]) & ((t1 - t0) <= 1.5 * dt)
    # with no gap between t and t - tau the index distance matches the time shift
    ok &= np.abs(i - np.arange(n)) * dt >= abs(tau) - 2.0 * dt
    return i, w, ok


def shift_array(x: np.ndarray, i: np.ndarray, w: np.ndarray) -> np.ndarray:
    """Linear interpolation of an (N, ...) array with :func:`shift_weights` along axis 0."""
    wb = w.reshape((-1,) + (1,) * (x.ndim - 1))
    out = x.take(i, axis=0)
    out *= 1.0 - wb
    upper = x.take(i + 1, axis=0)
    upper *= wb
    out += upper
    return out


def _time_indexed(v, n: int) -> bool:
    return isinstance(v, np.ndarray) and v.ndim >= 1 and v.shape[0] == n and v.dtype.kind == "f"


class ShiftedSignals(MutableMapping):
    """A dataset's ``signals`` seen at ``t - tau``: each time-indexed float signal is interpolated
    (:func:`shift_array`) when first read, then kept. A fit reads only the few signals its
    regressor needs (the nominal output, q, qd, qdd), so a probe of the outer search does not pay
    for the large column caches a dataset may carry (an ``(N, C, 80)`` block of link inertia
    columns). The keys are those of the source at the time of the shift; values written later
    (a cache an effect fills on first use) are kept as written."""

    def __init__(self, source: Mapping, i: np.ndarray, w: np.ndarray):
        self._source = dict(source)
        self._i, self._w, self._n = i, w, i.shape[0]
        self._done: dict = {}

    def __getitem__(self, key):
        if key not in self._done:
            v = self._source[key]
            self._done[key] = shift_array(v, self._i, self._w) if _time_indexed(v, self._n) else v
        return self._done[key]

    def __setitem__(self, key, value) -> None:
        self._source[key] = value
        self._done[key] = value

    def __delitem__(self, key) -> None:
        del self._source[key]
        self._done.pop(key, None)

    def __iter__(self):
        return iter(self._source)

    def __len__(self) -> int:
        return len(self._source)

    def __contains__(self, key) -> bool:
        return key in self._source


def _transform(ds: Dataset, values: Mapping[str, float]) -> Dataset:
    tau = float(values.get("tau", 0.0))
    if tau == 0.0 or ds.n < 2:
        return ds
    i, w, ok = shift_weights(ds.t, tau)
    n = ds.n

    def sh(v):
        return shift_array(v, i, w) if _time_indexed(v, n) else v

    shifted = ds.replace(signals=ShiftedSignals(ds.signals, i, w), act_vel=sh(ds.act_vel),
                         act_map=sh(ds.act_map), valid=ds.valid & ok)
    hook = _remeasure_hook(ds.plant)
    return shifted if hook is None else hook(ds, shifted)


def _remeasure_hook(plant: str):
    """The plant's ``remeasure`` hook, or None (also for a dataset of an unregistered plant)."""
    from ..errors import CablelabError
    from ..registry import get_plant

    try:
        return get_plant(plant).remeasure
    except CablelabError:
        return None


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
