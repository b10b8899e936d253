"""Leg controller laws (spec 003_leg.md sec. 5 "Controller").

* ``open_loop``: 003 eq. 26, ``tau = T sin(2 pi (t - t_d) / P)`` in stance, 0 in flight, restarted
  at each detected touch-down t_d.
* ``apex``: apex-height return-map controller. After each apex n,
  ``T_{n+1} = T_n + k_i (h_des - h_n) + k_ff (h_des - h_n) / |dh/dT|``, with ``dh/dT`` the
  sensitivity of the next apex height to T from the nominal hybrid model (central finite
  difference of one simulated stride from the measured apex, :class:`~.sim.LegSim`): a damped
  model-based Newton step plus an integral term that removes the model's steady error. T is
  limited to [0, T_max]; a stale or non-finite apex holds T.
"""
from __future__ import annotations

import math
from dataclasses import dataclass

from .hybrid import FLIGHT, STANCE, LegParams
from .sim import DT, LegSim, open_loop


def next_apex(p: LegParams, h: float, T: float, P: float, dt: float = DT, horizon: float = 1.5) -> float:
    """Height (m) of the apex after one stride of the hybrid model from an apex at height ``h``
    (at rest in flight) under eq. 26 with amplitude T; NaN if no apex within ``horizon`` s."""
    sim = _stepper(p, dt)
    sim.reset(h, 0.0, phase=FLIGHT)
    law = open_loop(T, P)
    q, v = sim._q, sim._v
    n = int(horizon / dt)
    seen_stance = False
    zp, vp = float(q[0]), float(v[0])
    for _ in range(n):
        tau = law(sim.t, sim) if sim.phase == STANCE else 0.0
        sim.step(tau)
        z, zd = float(q[0]), float(v[0])
        seen_stance = seen_stance or sim.phase == STANCE
        if seen_stance and sim.phase == FLIGHT and vp > 0.0 >= zd:
            # vertex of the parabola through the last two samples' heights and velocities
            a = vp / (vp - zd) if vp != zd else 0.0
            return zp + 0.5 * vp * a * dt
        zp, vp = z, zd
    return math.nan


def _stepper(p: LegParams, dt: float) -> LegSim:
    """One :class:`LegSim` per (parameters, period), reset for each stride (compiling the MuJoCo
    model took as long as simulating the stride)."""
    key = (p, dt)
    sim = _STEPPERS.get(key)
    if sim is None:
        if len(_STEPPERS) >= 16:
            _STEPPERS.clear()
        sim = _STEPPERS[key] = LegSim(p, p.z_td, 0.0, phase=FLIGHT, dt=dt)
    return sim


_STEPPERS: dict = {}


@dataclass
class ApexController:
    """Apex-height controller state (spec sec. 5). Gains: k_i N m/m, k_ff (-). T in N m, P in s."""

    params: LegParams
    h_des: float
    T: float = 1.0
    P: float = 0.30
    k_i: float = 10.0
    k_ff: float = 0.5
    T_max: float = 4.0
    dT: float = 0.02
    mode: str = "apex"

    def __post_init__(self):
        self._t_d = 0.0
        self._phase = FLIGHT
        self.last_sensitivity = math.nan
        self._apex_time = math.nan      # time of the last apex taken (see step)

    def sensitivity(self, h: float) -> float:
        """dh_{n+1}/dT at the apex height h, m/(N m) (central difference of two model strides)."""
        hp = next_apex(self.params, h, self.T + self.dT, self.P)
        hm = next_apex(self.params, h, max(self.T - self.dT, 0.0), self.P)
        return (hp - hm) / (self.T + self.dT - max(self.T - self.dT, 0.0))

    def on_apex(self, h: float) -> float:
        """Update T after a measured apex at height h (m); returns the new T."""
        if self.mode != "apex" or not math.isfinite(h):
            return self.T
        e = self.h_des - h
        s = self.sensitivity(h)
        self.last_sensitivity = s
        step = self.k_i * e
        if math.isfinite(s) and abs(s) > 1e-6:
            step += self.k_ff * e / abs(s)
        self.T = min(max(self.T + step, 0.0), self.T_max)
        return self.T

    def torque(self, t: float, phase: int) -> float:
        """Motor torque (N m) at time t for the estimated phase (eq. 26, restarted at touch-down)."""
        if phase == STANCE and self._phase != STANCE:
            self._t_d = t
        self._phase = phase
        if phase != STANCE:
            return 0.0
        return self.T * math.sin(2.0 * math.pi * (t - self._t_d) / self.P)

    def step(self, t: float, phase: int, apex_height: float, apex_time: float) -> float:
        """One hop estimate (``/leg/hop_estimate``: the last apex's height and time repeat until the
        next apex): a new apex updates T (:meth:`on_apex`, once per apex time), then the
        :meth:`torque` at ``t`` for ``phase``."""
        if math.isfinite(apex_time) and apex_time != self._apex_time:
            self._apex_time = apex_time
            self.on_apex(apex_height)
        return self.torque(t, phase)
