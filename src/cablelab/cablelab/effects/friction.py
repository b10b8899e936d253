"""Joint / actuator friction, generic over plants through the actuator -> channel map.

Per actuator j with velocity v_j (rad/s or m/s), the friction force/torque at the actuator is
``Fv_j v_j + Fc_j sign(v_j)`` (001 eq. 15 for the CDPR winches, 002 sec. 3 joint friction for the
crane, the EMPS reference model force = M qdd + Fv qd + Fc sign(qd) + OF). It reaches the output
channels through ``Dataset.act_map`` (identity for an axis or the crane joints).
"""
from __future__ import annotations

import numpy as np

from .base import Effect, Param, Physical, RegressorFn
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


# ----------------------------------------------------------------------------- Stribeck friction
# Stribeck law (CONTRACT sec. 4): F(v) = [F_c + (F_s - F_c) exp(-(v / v_s)^2)] sign(v). With the
# Coulomb column F_c sign(v) already in the model (joint/winch_coulomb_friction), the Stribeck
# effect adds the column exp(-(v / v_s)^2) sign(v) with the breakaway excess dFs = F_s - F_c
# (linear) and v_s searched outside the linear LS (separable LS). v_s is parameterised relative
# to the record's speed scale, ``vs_rel = v_s / p99(|v|)`` per actuator, so one bounded search
# range fits every plant and unit; the fitted v_s = vs_rel p99(|v|) is reported by the
# explanation. Samples in the zero-speed zone are excluded by the dataset (cablelab.velocity).

#: search range of v_s / p99(|v|)
STRIBECK_VS_REL = (0.02, 0.5)


def _stribeck_transform(ds, values):
    return ds.replace(signals={**ds.signals, "stribeck_vs_rel": float(values.get("vs_rel", 0.1))})


def stribeck_regressor(effect_id: str) -> RegressorFn:
    """Regressor ``exp(-(v / v_s)^2) sign(v)`` per actuator through the actuator map, v_s =
    ``vs_rel`` x the actuator's 99th-percentile speed."""
    def fn(ds):
        v = ds.require_actuators(effect_id)
        vs = float(ds.signals.get("stribeck_vs_rel", 0.1)) * np.maximum(
            np.percentile(np.abs(v), 99, axis=0), 1e-12)
        return ds.actuator_block(np.exp(-(v / vs) ** 2) * coulomb_sign(v))
    return fn


def stribeck_contract_params(effect: Effect, own: dict, all_params: dict, ds) -> dict:
    """The contract's Stribeck parameters beside the fitted ones: F_s = Fc + dFs (the model's
    Coulomb level, 0 without it) and v_s = vs_rel x p99(|v|), per actuator."""
    v = ds.require_actuators(effect.id)
    p99 = np.percentile(np.abs(v), 99, axis=0)
    vs_rel = float(own.get("vs_rel", 0.1))
    out = {}
    for j, col in enumerate(effect.columns(ds)):
        suffix = col.name[len("dFs"):]
        if col.name in own:
            out["F_s" + suffix] = float(all_params.get("Fc" + suffix, 0.0)) + float(own[col.name])
            out["v_s" + suffix] = vs_rel * float(p99[min(j, len(p99) - 1)])
    return out


def stribeck_physical(effect_id: str):
    """The contract's Stribeck parameters per actuator: F_s = F_c + dFs (the model's Coulomb
    level, 0 without it) and v_s = vs_rel x p99(|v|) (CONTRACT sec. 4)."""
    def fn(ds):
        eff_cols = [c for c in _stribeck_columns(effect_id, ds)]
        v = ds.require_actuators(effect_id)
        p99 = np.percentile(np.abs(v), 99, axis=0)
        out = []
        for j, col in enumerate(eff_cols):
            suffix = col.name[len("dFs"):]
            pos = ds.act_units[j][1] if j < len(ds.act_units) and ds.act_units[j][1] else "?"
            scale = float(p99[min(j, len(p99) - 1)])
            out.append(Physical("F_s" + suffix, col.unit,
                                lambda p, s=suffix, c=col.name: p.get("Fc" + s, 0.0) + p[c],
                                "Stribeck breakaway friction F_s (CONTRACT sec. 4)"))
            out.append(Physical("v_s" + suffix, f"{pos}/s", lambda p, k=scale: p["vs_rel"] * k,
                                "Stribeck speed v_s (CONTRACT sec. 4)"))
        return tuple(out)
    return fn


def _stribeck_columns(effect_id: str, ds):
    from . import get_effect

    return get_effect(effect_id).columns(ds)


def stribeck_effect(effect_id: str, plants: tuple, reference: str,
                    requires: str | None = None) -> Effect:
    """A Stribeck friction effect (generic: joint effects; the CDPR registers its winch one)."""
    return Effect(
        id=effect_id,
        plants=plants,
        requires=requires,
        params=(Param("dFs", "{effort}", 0.0, 0.0, np.inf,
                      "Stribeck breakaway excess F_s - F_c (F_s = F_c + dFs)"),),
        nonlinear=(Param("vs_rel", "1", 0.1, STRIBECK_VS_REL[0], STRIBECK_VS_REL[1],
                         "Stribeck speed v_s / p99(|v|)"),),
        transform=_stribeck_transform,
        explanation="friction is higher just after breakaway and falls to the Coulomb level "
                    "within the Stribeck speed v_s",
        signature="residual peaks at low speed just after reversals and starts, in the friction "
                  "direction",
        reference=reference,
        regressor=stribeck_regressor(effect_id),
        per_actuator=True,
        derived=stribeck_contract_params,
        physical=stribeck_physical(effect_id),
    )


JOINT_STRIBECK_FRICTION = register(stribeck_effect(
    "joint_stribeck_friction", ("*",), "CONTRACT sec. 4; Stribeck law (001 eq. 15 extended)",
    requires="joint_actuators"))
