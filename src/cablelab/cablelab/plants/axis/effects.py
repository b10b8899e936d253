"""Effects specific to the single-axis plant (the axis model of :mod:`cablelab.plants.axis`).

force = M qdd + Fv qd + Fc sign(qd) + OF (+ m c g sin q for a revolute joint, q = 0 hanging down)
(EMPS reference inverse model; CONTRACT section 3 ``axis.gravity_moment``). ``axis_inertia`` and
``axis_gravity`` are the rigid-body part; friction and offset are the generic effects.
"""
from __future__ import annotations

import numpy as np

from ...dataset import Dataset
from ...effects.base import Effect, Param
from ...effects import register


def _inertia(ds: Dataset) -> np.ndarray:
    return ds.require_signal("qdd").reshape(ds.n, 1, 1)


def _gravity(ds: Dataset) -> np.ndarray:
    return (ds.gravity * np.sin(ds.require_signal("q"))).reshape(ds.n, 1, 1)


def _described(field: str, name: str):
    """``ds -> {name: value}`` of the description's ``axis.<field>`` (empty when not given)."""
    def fn(ds: Dataset) -> dict:
        sec = getattr(ds.description, "axis", None) if ds.description is not None else None
        val = getattr(sec, field, None) if sec is not None else None
        return {} if val is None else {name: float(val)}
    return fn


AXIS_INERTIA = register(Effect(
    id="axis_inertia",
    plants=("axis",),
    params=(Param("M", "{inertia}", 0.0, 0.0, np.inf, "moving mass / inertia at the joint"),),
    explanation="the force needed to accelerate the moving mass (Newton: M qdd)",
    signature="residual follows the acceleration",
    reference="EMPS reference model (IDIM); 002 eq. 4.2 inertial parameters",
    regressor=_inertia,
    described=_described("inertia", "M"),
))

AXIS_GRAVITY = register(Effect(
    id="axis_gravity",
    plants=("axis",),
    params=(Param("mc", "kg m", 0.0, -np.inf, np.inf, "gravity moment m*c of a revolute load"),),
    explanation="gravity pulls a revolute load with torque m c g sin(q)",
    signature="residual follows sin(q), the joint angle from hanging down",
    reference="CONTRACT sec. 3 axis.gravity_moment; 002 eq. A.10 (gravity terms)",
    regressor=_gravity,
    described=_described("gravity_moment", "mc"),
))
