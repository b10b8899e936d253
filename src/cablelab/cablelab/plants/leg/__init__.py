"""Plant ``leg``: the parallel-elastic hopping leg of paper 003 (spec 003_leg.md).

Modules: :mod:`.hybrid` (phase model, guards, impact maps), :mod:`.sim` (MuJoCo plant with
event-located switches), :mod:`.reference` (scipy oracle for tests), :mod:`.estimator`,
:mod:`.controller`, :mod:`.identify` (staged NMSE identification, k-fold CV), :mod:`.effects`,
:mod:`.dataset` (workbench inverse model), :mod:`.description` (``leg:`` section).
"""
from __future__ import annotations

from ...registry import Plant, register_plant
from . import effects as _effects  # noqa: F401  (registers the leg effects)
from . import topics
from .dataset import check_bag, dataset
from .description import parse_section
from .topics import JOINT_STATE


def _baseline(description) -> tuple[str, ...]:
    return _effects.BASELINE


def _candidates(description) -> tuple[str, ...]:
    return _effects.BASELINE + _effects.CANDIDATES


LEG = register_plant(Plant(
    name="leg",
    topics=((topics.JOINT_STATES, JOINT_STATE),),
    dataset=dataset,
    baseline=_baseline,
    candidates=_candidates,
    channels_doc="body: s (F_in + k (z_0 - z)), the known vertical force on the body (N)",
    section=parse_section,
    contract_topics=topics.TYPES,                  # CONTRACT sec. 2, spec 003_leg.md sec. 5
    joint_topic=topics.JOINT_STATES,
    joints=("body", "motor"),
    checked_topics=(topics.CONTACT,),
    check_bag=check_bag,
    channels=("body",),
    topic_names=lambda desc: {topics.JOINT_STATES: ["body", "motor"], topics.CONTACT: ["contact"],
                              **{t: ["height", "phase", "apex_height", "grf"] for t in
                                 (topics.HOP_ESTIMATE, topics.GROUND_TRUTH)}},
    markers=lambda bag, desc: _bag_markers(bag, desc),
))


def _bag_markers(bag, desc):
    from .markers import bag_markers

    return bag_markers(bag, desc)

PLANT = LEG
