"""Plant ``leg``: the parallel-elastic hopping leg of paper 003 (spec 003_leg.md).

Modules: :mod:`.hybrid` (phase model, guards, impact maps), :mod:`.sim` (MuJoCo plant with
event-located switches), :mod:`.reference` (scipy oracle for tests), :mod:`.estimator`,
:mod:`.controller`, :mod:`.identify` (staged NMSE identification, k-fold CV), :mod:`.effects`,
:mod:`.dataset` (workbench inverse model), :mod:`.description` (``leg:`` section).
"""
from __future__ import annotations

from .. import Plant, register_plant
from . import effects as _effects  # noqa: F401  (registers the leg effects)
from .dataset import dataset


def _baseline(description) -> tuple[str, ...]:
    return _effects.BASELINE


def _candidates(description) -> tuple[str, ...]:
    return _effects.BASELINE + _effects.CANDIDATES


LEG = register_plant(Plant(
    name="leg",
    topics=(("/leg/joint_states", "sensor_msgs/msg/JointState"),),
    dataset=dataset,
    baseline=_baseline,
    candidates=_candidates,
    channels_doc="body: s (F_in + k (z_0 - z)), the known vertical force on the body (N)",
))
