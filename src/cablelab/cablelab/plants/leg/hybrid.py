"""The hybrid phase model of the parallel-elastic hopping leg (paper 003, spec 003_leg.md sec. 3).

State x = [z, zdot]: body (CoM) height above the ground (m) and its rate (m/s).

* Stance (003 eq. 1): ``m zdd = F_in + F_s(z) - d_s zdot - m_f g`` with the spring force
  ``F_s = k (z_0 - z) (1 + k_2 (z_0 - z) + k_3 (z_0 - z)^2) + F_0`` (003 eq. 1 is ``k (z_0 - z)``;
  ``F_0``, ``k_2``, ``k_3`` are the candidate effects ``spring_preload`` / ``spring_nonlinearity``,
  zero in the nominal model).
* Flight (003 eq. 23): ``m_f zdd = -d_f zdot - m_f g`` (``m_f = m`` unless ``phase_effective_mass``).
  ``m_f`` is the leg's mass (what a scale weighs: gravity acts on it in both phases); ``m`` is
  the stance inertia, which the link rotation raises above ``m_f`` (003 sec. 3.4, E9). Flight
  alone only sees ``d_f / m_f``; the two masses differ visibly in stance, where the inertia
  ``m`` multiplies zdd and the weight ``m_f g`` does not.
* Input (003 eq. 3): ``F_in = tau / (2 L sin theta)`` with ``cos theta = z / 2L`` (eq. 2), i.e.
  ``F_in = tau / sqrt(4 L^2 - z^2)``.
* Ground reaction force (003 eq. 25): ``F_GRF = F_in + F_s(z) - d_s zdot``.
* Touch-down: z crosses ``l_fl`` downwards, then ``zdot+ = beta_td zdot-`` (003 eq. 24).
* Lift-off: F_GRF reaches 0 or z crosses ``z_td`` upwards (checked only after the first sample
  of stance), then ``zdot+ = beta_lo zdot-`` and the leg length is frozen in flight at
  ``l_fl = min(z_td, z_lo)`` (spec defect E1: 003's literal rule lets the body fall through).
* Excitation (003 eq. 26): ``tau = T sin(2 pi (t - t_d) / P)`` in stance, 0 in flight.

All functions are plain numpy (vectorised over samples where it makes sense); the MuJoCo stepper
(:mod:`.sim`) and the scipy oracle (:mod:`.reference`) both evaluate these same laws.
"""
from __future__ import annotations

import dataclasses
import functools
import math
from dataclasses import dataclass

import numpy as np

FLIGHT = 0
STANCE = 1
TOUCHDOWN = "touchdown"
LIFTOFF = "liftoff"


@dataclass(frozen=True)
class LegParams:
    """Hybrid model parameters (SI). Defaults: 003 Table 2, k = 605 N/m (sec. 3.3), spec 003 sec. 2.

    Args:
        m: lumped mass (stance inertia), kg. k: equivalent vertical stiffness, N/m.
        d_s, d_f: stance / flight damping, N s/m. beta_td, beta_lo: velocity ratios (eq. 24).
        g: gravity, m/s^2. L: link length, m (spec E2). theta0: free-length half angle, rad.
        z0: spring rest position, m (None = z_td). F0: spring preload at z0, N.
        k2, k3: cam nonlinearity, 1/m and 1/m^2. Fc: guide Coulomb friction, N.
        m_f: the leg's (weighed) mass: flight inertia and weight in both phases, kg (None = m).
    """

    m: float = 1.55
    k: float = 605.0
    d_s: float = 6.35
    d_f: float = 1.18
    beta_td: float = 0.57
    beta_lo: float = 1.13
    g: float = 9.81
    L: float = 0.15
    theta0: float = 0.349066
    z0: float | None = None
    F0: float = 0.0
    k2: float = 0.0
    k3: float = 0.0
    Fc: float = 0.0
    m_f: float | None = None

    @functools.cached_property
    def z_td(self) -> float:
        """Free leg length = touch-down height ``2 L cos theta_0`` (003 eq. 2), m."""
        return 2.0 * self.L * math.cos(self.theta0)

    @functools.cached_property
    def spring_rest(self) -> float:
        """z_0, m (spec: = z_td unless given)."""
        return self.z_td if self.z0 is None else float(self.z0)

    @property
    def flight_mass(self) -> float:
        return self.m if self.m_f is None else float(self.m_f)

    def replace(self, **changes) -> "LegParams":
        return dataclasses.replace(self, **changes)

    def no_impact(self) -> "LegParams":
        """003 Fig. 11 'model without impact': beta_td = beta_lo = 1."""
        return self.replace(beta_td=1.0, beta_lo=1.0)


# ----------------------------------------------------------------------------- constants (B1)

def stance_omega(p: LegParams) -> float:
    """Undamped stance natural frequency sqrt(k/m), rad/s."""
    return math.sqrt(p.k / p.m)


def stance_zeta(p: LegParams) -> float:
    """Stance damping ratio d_s / (2 sqrt(k m))."""
    return p.d_s / (2.0 * math.sqrt(p.k * p.m))


def static_deflection(p: LegParams) -> float:
    """Static spring deflection m_f g / k, m (stance equilibrium ``z_eq = z_0 - m_f g / k`` at F_0 = 0)."""
    return p.flight_mass * p.g / p.k


# ----------------------------------------------------------------------------- forces
# Plain arithmetic: the same functions take Python floats (the 1 kHz stepper, no numpy overhead)
# or numpy arrays over time (batch evaluation, estimator, identification).

def _sign(x):
    return (x > 0) * 1.0 - (x < 0) * 1.0


def input_force(tau, z, p: LegParams):
    """F_in = tau / (2 L sin theta), theta = acos(z / 2L) (003 eq. 2-3), N. ``tau`` in N m."""
    d = 4.0 * p.L * p.L - z * z  # (2 L sin theta)^2; <= 0 only above the fully extended leg
    d = (d if d > 1e-12 else 1e-12) if type(d) is float else np.maximum(d, 1e-12)
    return tau / d ** 0.5


def spring_force(z, p: LegParams):
    """Parallel spring force on the body, N (003 eq. 1 plus preload / cam nonlinearity effects)."""
    e = p.spring_rest - z
    return p.k * e * (1.0 + p.k2 * e + p.k3 * e * e) + p.F0


def grf(z, zd, f_in, p: LegParams):
    """Ground reaction force F_GRF = F_in + k (z_0 - z) - d_s zdot (003 eq. 25), N."""
    return f_in + spring_force(z, p) - p.d_s * zd


def stance_accel(z, zd, f_in, p: LegParams):
    """zdd in stance (003 eq. 1; the weight ``m_f g`` over the stance inertia ``m``), m/s^2."""
    return (grf(z, zd, f_in, p) - p.Fc * _sign(zd)) / p.m - p.g * (p.flight_mass / p.m)


def flight_accel(zd, p: LegParams):
    """zdd in flight (003 eq. 23), m/s^2."""
    return -(p.d_f * zd + p.Fc * _sign(zd)) / p.flight_mass - p.g


# ----------------------------------------------------------------------------- guards and maps

def liftoff_guard(z, zd, f_in, p: LegParams):
    """Stance guard ``min(F_GRF / k, z_td - z)`` (m): lift-off where it crosses 0 downwards
    (003 sec. 2.3: F_GRF = 0 or z at the free length). F_GRF is scaled by 1/k to a length so the
    linear event interpolation of both branches is in the same unit."""
    a, b = grf(z, zd, f_in, p) / p.k, p.z_td - z
    if type(a) is float:
        return a if a < b else b
    return np.minimum(a, b)


def touchdown_map(zd, p: LegParams) -> float:
    """zdot+ = beta_td zdot- (003 eq. 24)."""
    return p.beta_td * zd


def liftoff_map(z, zd, p: LegParams) -> tuple[float, float]:
    """(zdot+, l_fl): zdot+ = beta_lo zdot- (003 eq. 24), frozen leg length min(z_td, z) (E1)."""
    return p.beta_lo * zd, min(p.z_td, float(z))


# ----------------------------------------------------------------------------- closed forms

def flight_closed_form(t, z0: float, v0: float, p: LegParams) -> tuple[np.ndarray, np.ndarray]:
    """Damped free flight (spec sec. 3): ``zdot = (v0 + g m/d_f) e^{-d_f t/m} - g m/d_f`` and its
    integral. Returns (z(t), zdot(t)); ``d_f = 0`` gives the ballistic parabola."""
    t = np.asarray(t, float)
    m = p.flight_mass
    if p.d_f <= 0:
        return z0 + v0 * t - 0.5 * p.g * t * t, v0 - p.g * t
    tau = m / p.d_f
    vinf = p.g * tau
    e = np.exp(-t / tau)
    return z0 + (v0 + vinf) * tau * (1.0 - e) - vinf * t, (v0 + vinf) * e - vinf


def flight_apex(z0: float, v0: float, p: LegParams) -> tuple[float, float]:
    """(time after the start, height) of the flight apex from (z0, v0 > 0), closed form."""
    if v0 <= 0:
        return 0.0, z0
    m = p.flight_mass
    if p.d_f <= 0:
        ta = v0 / p.g
    else:
        tau = m / p.d_f
        ta = tau * math.log(1.0 + v0 / (p.g * tau))
    z, _ = flight_closed_form(ta, z0, v0, p)
    return float(ta), float(z)
