"""Effects of the hopping leg (spec 003_leg.md sec. 7), registered by id for the workbench.

All are columns of the inverse model of :mod:`.dataset` (``y = s (F_in + k (z_0 - z))`` =
sum of effect terms), built from the dataset's parallel-filtered bases. ``leg_inertia`` (m) with
``stance_damping`` and ``flight_damping`` is the baseline (003's model without the impact map);
the rest are the diagnose candidates. ``contact_delay`` has no column: its nonlinear parameter
tau_c rebuilds the dataset with the switch advanced by tau_c (:func:`.dataset.advance_contact`),
searched outside the linear least squares like ``time_delay``.
"""
from __future__ import annotations

import numpy as np

from ...effects import register
from ...effects.base import Physical
from ...dataset import Dataset
from ...effects.base import Effect, Param


def _cols(*names):
    def fn(ds: Dataset) -> np.ndarray:
        return np.stack([ds.require_signal(n) for n in names], axis=1)[:, None, :]
    return fn


def _neg(name):
    def fn(ds: Dataset) -> np.ndarray:
        return -ds.require_signal(name).reshape(ds.n, 1, 1)
    return fn


LEG = ("leg",)

register(Effect(
    id="leg_inertia", plants=LEG,
    params=(Param("m", "kg", 1.55, 0.0, np.inf, "lumped (effective) mass"),),
    explanation="the lumped mass accelerated against gravity: m (zdd + g)",
    signature="residual follows the body acceleration",
    reference="003 eq. 1 and 23", regressor=_cols("acc")))

register(Effect(
    id="stance_damping", plants=LEG,
    params=(Param("d_s", "N s/m", 6.35, 0.0, 30.0, "stance damping"),),
    explanation="viscous damping of the leg in stance, d_s zdot",
    signature="stance amplitude decays faster than the model; residual in phase with zdot in stance",
    reference="003 eq. 1, Table 2", regressor=_cols("zd_stance")))

register(Effect(
    id="flight_damping", plants=LEG,
    params=(Param("d_f", "N s/m", 1.18, 0.0, 10.0, "flight damping"),),
    explanation="viscous drag of the guide in flight, d_f zdot",
    signature="flight velocity residual linear in zdot; ascent and descent times unequal",
    reference="003 eq. 23, Table 2", regressor=_cols("zd_flight")))

register(Effect(
    id="impact_restitution", plants=LEG,
    params=(Param("c_td", "kg", 0.0, -np.inf, np.inf, "m (1 - beta_td): momentum lost at touch-down"),
            Param("c_lo", "kg", 0.0, -np.inf, np.inf, "m (1 - beta_lo): momentum change at lift-off")),
    explanation="abrupt velocity change at touch-down and lift-off, zdot+ = beta zdot- "
                "(beta = 1 - c / m)",
    signature="velocity residual jumps at contact-switch edges; apex height and time errors",
    reference="003 eq. 24, Table 2", regressor=_cols("impulse_td", "impulse_lo"),
    # the columns are momentum changes m (1 - beta) zdot-: the paper's velocity ratios are
    # beta = 1 - c / m with m the leg's mass (leg_inertia, fitted or weighed)
    physical=lambda ds: (
        Physical("beta_td", "1", lambda p: 1.0 - p["c_td"] / p["m"],
                 "touch-down velocity ratio zdot+ / zdot- (003 eq. 24, Table 2: 0.57)"),
        Physical("beta_lo", "1", lambda p: 1.0 - p["c_lo"] / p["m"],
                 "lift-off velocity ratio zdot+ / zdot- (003 eq. 24, Table 2: 1.13)"))))

register(Effect(
    id="spring_preload", plants=LEG,
    params=(Param("F0", "N", 0.0, 0.0, 10.0, "spring force offset (pretension)"),),
    explanation="the tension spring's pretension: a constant force F_0 in stance",
    signature="stance equilibrium shifted by F_0/k; GRF not 0 at touch-down",
    reference="003 sec. 3.3, Fig. 8 ('605 N/m + 2.7 N')", regressor=_neg("stance")))

register(Effect(
    id="spring_nonlinearity", plants=LEG,
    params=(Param("k2", "1/m", 0.0, -10.0, 10.0, "quadratic cam error"),
            Param("k3", "1/m^2", 0.0, -500.0, 500.0, "cubic cam error")),
    explanation="cam linearisation error: k (z0 - z)(1 + k2 (z0 - z) + k3 (z0 - z)^2)",
    signature="stance frequency depends on amplitude; residual at 2x and 3x the stance frequency",
    reference="003 sec. 2.2 eq. 4-5 (cam design)", regressor=lambda ds: -_cols("e2", "e3")(ds)))

register(Effect(
    id="guide_coulomb_friction", plants=LEG,
    params=(Param("Fc", "N", 0.0, 0.0, 3.0, "guide Coulomb friction"),),
    explanation="dry friction of the linear guide and rack, F_c sign(zdot)",
    signature="constant-magnitude residual switching sign at the apex and the stance bottom",
    reference="003 sec. 3.1 (linear bearing, rack and pinion)", regressor=_cols("sign")))

register(Effect(
    id="phase_effective_mass", plants=LEG,
    params=(Param("dm_f", "kg", 0.0, -0.4, 0.4, "flight mass minus stance mass m_f - m_s"),),
    explanation="link rotation adds inertia in stance only: the stance inertia m_s differs from the "
                "leg's mass m_f (``leg_inertia`` m), which flight and the weight m_f g see: "
                "m_s zdd + m_f g = m_f (zdd + g) - (m_f - m_s) zdd in stance",
    signature="stance frequency against the weighed mass (003: 1.62 kg); residual in phase with the "
              "stance acceleration; explains beta_lo > 1 (E9)",
    reference="003 sec. 3.3-3.4 (m 1.55 estimated vs 1.62 kg weighed, beta_lo > 1)",
    regressor=_neg("acc_stance"),
    physical=lambda ds: (
        Physical("m_s", "kg", lambda p: p["m"] - p["dm_f"],
                 "stance inertia (spec 003 sec. 7: m_s)"),
        Physical("m_f", "kg", lambda p: p["m"],
                 "flight inertia and weight, the leg's mass (spec 003 sec. 7: m_f)"))))


def _contact_delay(ds: Dataset, values) -> Dataset:
    from .dataset import advance_contact

    return advance_contact(ds, float(values.get("tau_c", 0.0)))


register(Effect(
    id="contact_delay", plants=LEG, params=(),
    explanation="the contact switch closes and opens tau_c after the true touch-down and lift-off",
    signature="velocity jump earlier than the switch edge; F_GRF estimate negative before lift-off",
    reference="003 sec. 3.1 (contact switch); spec 003_leg.md sec. 7",
    nonlinear=(Param("tau_c", "s", 0.0, 0.0, 0.020, "delay of the contact switch behind the true "
                     "transition"),),
    transform=_contact_delay))

BASELINE = ("leg_inertia", "stance_damping", "flight_damping")
CANDIDATES = ("impact_restitution", "spring_preload", "spring_nonlinearity", "guide_coulomb_friction",
              "phase_effective_mass", "contact_delay")
