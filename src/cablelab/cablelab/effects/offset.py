"""Constant bias on a measured actuator effort (any plant).

A torque/force sensor (or a current-based torque estimate) reads ``effort + OF``; seen through
the actuator -> channel map this adds the column ``A(t)[:, :, j]`` per actuator. 002 sec. 6.5
found such an offset (-0.2 N m on the slew torque at rest); the EMPS reference model has OF.
"""
from __future__ import annotations

import numpy as np

from ..dataset import Dataset
from .base import Effect, Param
from . import register


def _offset(ds: Dataset) -> np.ndarray:
    n_act = ds.act_vel.shape[1] if ds.act_vel is not None else ds.n_channels
    return ds.actuator_block(np.ones((ds.n, n_act)))


TORQUE_SENSOR_OFFSET = register(Effect(
    id="torque_sensor_offset",
    plants=("*",),
    params=(Param("OF", "{effort}", 0.0, -np.inf, np.inf, "constant bias of the measured effort"),),
    explanation="the measured effort carries a constant bias",
    signature="residual has a non-zero mean, also at rest",
    reference="002 sec. 6.5; EMPS reference model",
    regressor=_offset,
    per_actuator=True,
))
