"""Experiment design for the crane (``cablelab excite``): the safe envelope and the dataset of a
designed motion."""
from __future__ import annotations

import numpy as np

from ...excite import Exciter, Limits
from ...dataset import STANDARD_GRAVITY, Dataset
from .dataset import JOINTS
from .topics import REFERENCE
from .dynamics_generated import regressor

#: the lab crane's safe envelope for designed excitations (slew rad, luff rad, hoist m): the
#: range the simulated crane's default excitation spans (sim.reference_trajectory) widened to
#: what its drives reach without saturating (sim.CraneTruth.effort_limit)
EXCITE_LOWER = (-1.0, 0.2, 0.3)
EXCITE_UPPER = (1.0, 1.0, 1.0)
EXCITE_SPEED = (0.6, 0.4, 0.6)
EXCITE_ACCEL = (1.0, 0.8, 3.0)


def excite_limits(description):
    return Limits(JOINTS, np.array(EXCITE_LOWER), np.array(EXCITE_UPPER), np.array(EXCITE_SPEED),
                  np.array(EXCITE_ACCEL))


def motion_dataset(t, q, qd, qdd, description) -> Dataset:
    """The crane dataset of a motion that follows the reference exactly, payload hanging still
    (swing angles 0): the regressor the effects see, outputs zero."""
    n = len(t)
    z = np.zeros((n, 2))
    q5, qd5, qdd5 = (np.column_stack([a, z]) for a in (q, qd, qdd))
    g = description.gravity if description is not None else STANDARD_GRAVITY
    return Dataset(plant="crane", t=np.asarray(t, float), y=np.zeros((n, 3)), channels=JOINTS,
                   units=("N m", "N m", "N"),
                   signals={"q": q5, "qd": qd5, "qdd": qdd5, "Y": regressor(q5, qd5, qdd5, g),
                            "boom_length": description.crane.boom_length if description is not None else 1.0},
                   actuators=JOINTS, act_vel=qd5[:, :3],
                   act_units=(("N m", "rad"), ("N m", "rad"), ("N", "m")),
                   description=description, source="designed motion")


#: the crane's experiment design (``cablelab excite``), registered by the package
EXCITER = Exciter(limits=excite_limits, motion_dataset=motion_dataset, reference_topic=REFERENCE,
                  base_hz=0.1, harmonics=6)
