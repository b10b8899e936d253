"""The leg as the simulator node runs it (ROS-free): the hybrid plant (:class:`.sim.LegSim`) with
true parameters of its own, read one sample at a time through the hardware's measurement model
(003 sec. 3.1: encoder height quantised to its resolution, velocity by backward difference)."""
from __future__ import annotations

import math

from .description import leg_of
from .hybrid import STANCE
from .sim import LegSim, motor_angle, quantise

__all__ = ["LiveLeg"]


class LiveLeg:
    """``step(tau)``: one period with motor torque ``tau`` (applied in stance only, as on the
    hardware) and the encoder reading.

    Args:
        description: the loaded description (its ``leg`` section and gravity: the nominal leg).
        mass_scale: true mass / the description's.
        preload: true spring preload F_0, N (NaN: the description's).
        z0_offset: start height above the touch-down height z_td, m.
        rate: simulation and sampling rate, Hz.
    """

    def __init__(self, description, mass_scale: float = 1.0, preload: float = math.nan,
                 z0_offset: float = 0.03, rate: float = 1000.0):
        leg = leg_of(description)
        nominal = leg.params(description.gravity)
        truth = nominal.replace(m=nominal.m * mass_scale, F0=nominal.F0 if math.isnan(preload) else preload)
        self.sim = LegSim(truth, nominal.z_td + z0_offset, 0.0, dt=1.0 / rate)
        self.resolution, self.rate = leg.encoder_resolution, rate
        self.z_prev: float | None = None
        self.zd = 0.0

    def reading(self) -> tuple[float, float, float]:
        """The encoder reading of the current state without stepping: ``(z, zd, theta)`` as
        :meth:`step` returns it (velocity 0 before the first step)."""
        z = float(quantise(self.sim.z, self.resolution))
        return z, self.zd, float(motor_angle(z, self.sim.p.L))

    def step(self, tau: float) -> tuple[float, float, float]:
        """Advance one period; ``(z, zd, theta)``: the encoder height (m), its backward-difference
        velocity (m/s, 0 at the first sample) and the motor angle it implies (rad)."""
        s = self.sim
        s.step(tau if s.phase == STANCE else 0.0)
        z = float(quantise(s.z, self.resolution))
        self.zd = 0.0 if self.z_prev is None else (z - self.z_prev) * self.rate
        self.z_prev = z
        return z, self.zd, float(motor_angle(z, s.p.L))
