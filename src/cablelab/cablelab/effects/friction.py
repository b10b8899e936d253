"""Joint / actuator friction, generic over plants through the actuator -> channel map.

Per actuator j with velocity v_j (rad/s or m/s), the friction force/torque at the actuator is
``Fv_j v_j + Fc_j sign(v_j)`` (001 eq. 15 for the CDPR winches, 002 sec. 3 joint friction for the
crane, the EMPS reference model force = M qdd + Fv qd + Fc sign(qd) + OF). It reaches the output
channels through ``Dataset.act_map`` (identity for an axis or the crane joints).
"""
from __future__ import annotations

import numpy as np

from .base import Effect, Param, RegressorFn
from . import register

#: velocities below this magnitude (in the actuator's unit/s) count as "at rest" for sign(v):
#: sign(v) = 0 there. Zero keeps the textbook sign function.
COULOMB_DEADBAND = 0.0


def coulomb_sign(v, deadband: float = COULOMB_DEADBAND) -> np.ndarray:
    """sign(v) with a dead band |v| < deadband -> 0 (stiction zone; deadband in the unit of v).

    The Coulomb friction term of every plant (001 eq. 15 winches, the joints of the axis and the
    crane) and of the live laws built on them."""
    v = np.asarray(v, dtype=float)
    s = np.sign(v)
    if deadband > 0:
        s = np.where(np.abs(v) < deadband, 0.0, s)
    return s


def viscous_regressor(effect_id: str) -> RegressorFn:
    """Regressor of a viscous friction effect: ``ds -> (N, C, n_act)`` block of the actuator
    velocities ``v_j`` (rad/s or m/s) through the actuator -> channel map (001 eq. 15, F_v term).
    ``effect_id`` names the effect in the error raised when the plant has no actuator velocities."""
    return lambda ds: ds.actuator_block(ds.require_actuators(effect_id))


def coulomb_regressor(effect_id: str) -> RegressorFn:
    """Regressor of a Coulomb friction effect: ``ds -> (N, C, n_act)`` block of
    :func:`coulomb_sign` of the actuator velocities (001 eq. 15, F_c term)."""
    return lambda ds: ds.actuator_block(coulomb_sign(ds.require_actuators(effect_id)))


JOINT_VISCOUS_FRICTION = register(Effect(
    id="joint_viscous_friction",
    plants=("*",),
    requires="joint_actuators",
    params=(Param("Fv", "{effort} s/{position}", 0.0, 0.0, np.inf, "viscous friction coefficient"),),
    explanation="a force opposing motion in proportion to the actuator velocity",
    signature="residual grows in proportion to velocity",
    reference="001 eq. 15; 002 sec. 3",
    regressor=viscous_regressor("joint_viscous_friction"),
    per_actuator=True,
))

JOINT_COULOMB_FRICTION = register(Effect(
    id="joint_coulomb_friction",
    plants=("*",),
    requires="joint_actuators",
    params=(Param("Fc", "{effort}", 0.0, 0.0, np.inf, "Coulomb (dry) friction level"),),
    explanation="a constant force opposing motion, changing sign with the velocity",
    signature="residual jumps at velocity reversals",
    reference="001 eq. 15; EMPS reference model",
    regressor=coulomb_regressor("joint_coulomb_friction"),
    per_actuator=True,
))
