"""Boom-crane parameters and rigid-body dynamics over the 9 parameter groups of 002 eq. 4.2.

``tau = Y(q, qd, qdd) pi`` (002 eq. 4.1) with ``Y`` generated from the energies of 002 eq. A.3-A.4
(:mod:`cablelab.plants.crane.dynamics_generated`, written by :mod:`~cablelab.plants.crane.symbolic`).
q = [alpha, beta, d, theta1, theta2] (rad, rad, m, rad, rad); tau = [slew torque N m, luff torque
N m, hoist force N, 0, 0] (002 eq. 3.4: the swing joints are not actuated).
"""
from __future__ import annotations

from dataclasses import dataclass, replace

import numpy as np

from .dynamics_generated import PARAM_GROUPS, regressor

__all__ = ["CraneParams", "PARAM_GROUPS", "GROUP_UNITS", "regressor", "inverse_dynamics",
           "gravity_vector", "mass_matrix", "JOINTS", "SWING"]

#: actuated joints (CONTRACT sec. 2 names) and the passive swing coordinates
JOINTS = ("slew", "luff", "hoist")
SWING = ("theta1", "theta2")
GROUP_UNITS = ("kg m^2", "kg m^2", "kg m^2", "kg m", "kg", "kg m", "kg m^2", "kg m^2", "kg m")


@dataclass(frozen=True)
class CraneParams:
    """Physical parameters of the crane of 002 Table 3.2 (SI units).

    Args:
        boom_length: l_b, m (luff pivot to boom-tip pivot).
        payload_mass: m, kg (point mass, assumption 3).
        boom_mass: m_b, kg (uniform boom: centre of mass at l_b / 2, 002 eq. A.1).
        counterbalance_mass: m_c, kg, point mass at l_c behind the luff pivot (002 sec. 3.1).
        counterbalance_distance: l_c, m.
        slew_inertia: I_tot, kg m^2, constant inertia about the slew axis (002 eq. A.1).
        luff_inertia: I_b, kg m^2, constant inertia about the luff axis (002 eq. A.1).
        gravity: g, m/s^2.
    """

    boom_length: float = 1.0
    payload_mass: float = 0.5
    boom_mass: float = 1.0
    counterbalance_mass: float = 2.0
    counterbalance_distance: float = 0.3
    slew_inertia: float = 0.05
    luff_inertia: float = 0.02
    gravity: float = 9.81

    @classmethod
    def from_description(cls, desc, **overrides) -> "CraneParams":
        """Parameters from a :class:`~cablelab.description.Description` (crane section).

        Missing optional masses keep the defaults of this class; an absent counterbalance
        (``counterbalance`` unknown, CONTRACT sec. 3) is m_c = 0 in the model.
        """
        c = desc.crane
        kw = {"boom_length": c.boom_length, "gravity": desc.gravity}
        if c.payload_mass is not None:
            kw["payload_mass"] = c.payload_mass
        if c.boom_mass is not None:
            kw["boom_mass"] = c.boom_mass
        if c.counterbalance is None:
            kw["counterbalance_mass"], kw["counterbalance_distance"] = 0.0, 0.0
        else:
            kw["counterbalance_mass"] = c.counterbalance.mass
            kw["counterbalance_distance"] = c.counterbalance.distance
        kw.update(overrides)
        return cls(**kw)

    def groups(self) -> np.ndarray:
        """(9,) pi of 002 eq. 4.2: [I_tot, l_b^2 m_b, l_b^2 m, l_b m, m, l_b m_b, I_b, l_c^2 m_c, l_c m_c]."""
        lb, m, mb = self.boom_length, self.payload_mass, self.boom_mass
        lc, mc = self.counterbalance_distance, self.counterbalance_mass
        return np.array([self.slew_inertia, lb * lb * mb, lb * lb * m, lb * m, m, lb * mb,
                         self.luff_inertia, lc * lc * mc, lc * mc])

    @property
    def first_moment(self) -> float:
        """K = l_b m + l_b m_b / 2 - l_c m_c, kg m: the boom-side mass moment (002 eq. 6.9, G_2 / (g cos beta))."""
        return (self.boom_length * self.payload_mass + 0.5 * self.boom_length * self.boom_mass
                - self.counterbalance_distance * self.counterbalance_mass)

    def replace(self, **kw) -> "CraneParams":
        return replace(self, **kw)


def inverse_dynamics(q, qd, qdd, params: CraneParams) -> np.ndarray:
    """(N, 5) generalised forces M qdd + C qd + G (002 eq. 3.5) = Y pi."""
    return regressor(q, qd, qdd, params.gravity) @ params.groups()


def gravity_vector(q, params: CraneParams) -> np.ndarray:
    """(N, 5) G(q) (002 eq. 6.9)."""
    q = np.atleast_2d(np.asarray(q, dtype=float))
    z = np.zeros_like(q)
    return regressor(q, z, z, params.gravity) @ params.groups()


def mass_matrix(q, params: CraneParams) -> np.ndarray:
    """(N, 5, 5) inertia matrix M(q) of 002 eq. 3.5 (columns = Y(q, 0, e_k) pi with g = 0)."""
    q = np.atleast_2d(np.asarray(q, dtype=float))
    n = q.shape[0]
    z = np.zeros_like(q)
    pi = params.groups()
    out = np.empty((n, 5, 5))
    for k in range(5):  # 5 vectorised evaluations, not a loop over samples
        e = np.zeros_like(q)
        e[:, k] = 1.0
        out[:, :, k] = regressor(q, z, e, 0.0) @ pi
    return out
