"""Experiment design for the single axis (``cablelab excite``): the safe envelope and the dataset
of a designed motion.

The ``axis:`` description holds no travel range, so designed excitations stay inside a safe
envelope per joint type (documented below): the range, speed and acceleration the simulated
axis's default excitation spans (:func:`.truth.reference`, amplitude 0.2) with a little room.
A real drive with a shorter rail or slower limits needs its own envelope; the designed motion
is scaled into whatever :func:`excite_limits` returns.
"""
from __future__ import annotations

import numpy as np

from ...dataset import STANDARD_GRAVITY, Dataset
from ...excite import Exciter, Limits
from .topics import REFERENCE

#: the safe envelope of a designed excitation per joint type: (lower, upper, speed, acceleration)
#: in m, m/s, m/s^2 (prismatic) or rad, rad/s, rad/s^2 (revolute; q = 0 hanging down, so the
#: +-1.2 rad range sweeps the gravity load sin(q) over +-0.93)
EXCITE_ENVELOPE = {"prismatic": (-0.25, 0.25, 1.0, 5.0), "revolute": (-1.2, 1.2, 2.0, 8.0)}


def excite_limits(description) -> Limits:
    ax = description.axis if description is not None else None
    lo, hi, v, a = EXCITE_ENVELOPE[ax.joint_type if ax is not None else "prismatic"]
    return Limits(("joint",), np.array([lo]), np.array([hi]), np.array([v]), np.array([a]))


def effort_bound(description, viscous: float, coulomb: float, offset: float = 0.0) -> float:
    """Largest effort a motion inside :func:`excite_limits` can need (N or N m): ``M a_max +
    Fv v_max + Fc + |OF|`` (+ ``m c g`` for a revolute load), with M from the description."""
    lim = excite_limits(description)
    ax = description.axis
    g = description.gravity if description.gravity else STANDARD_GRAVITY
    return float((ax.inertia or 0.0) * lim.accel[0] + viscous * lim.speed[0] + coulomb + abs(offset)
                 + abs(ax.gravity_moment) * g)


def motion_dataset(t, q, qd, qdd, description) -> Dataset:
    """The axis dataset of a motion that follows the reference exactly (output zero): the
    regressor the effects see (:func:`.dataset.dataset_from_arrays` without the filtering, the
    motion being exact), the zero-speed zone left out as a recording's would be."""
    from ...velocity import exclude_zero_speed

    revolute = description.axis is not None and description.axis.joint_type == "revolute"
    unit = "N m" if revolute else "N"
    q, qd, qdd = (np.asarray(a, float).reshape(-1) for a in (q, qd, qdd))
    ds = Dataset(plant="axis", t=np.asarray(t, float), y=np.zeros((len(q), 1)), channels=("joint",),
                 units=(unit,), signals={"q": q, "qd": qd, "qdd": qdd, "rest_velocity": qd[:, None]},
                 actuators=("joint",), act_vel=qd[:, None],
                 act_units=((unit, "rad" if revolute else "m"),),
                 inputs={"velocity": qd, "acceleration": qdd},
                 description=description, source="designed motion")
    return exclude_zero_speed(ds, floor=1e-3 * excite_limits(description).speed[0])


#: the axis's experiment design (``cablelab excite``), registered by the package
EXCITER = Exciter(limits=excite_limits, motion_dataset=motion_dataset, reference_topic=REFERENCE,
                  base_hz=0.1, harmonics=5)
