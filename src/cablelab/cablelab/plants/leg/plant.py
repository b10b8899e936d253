"""The hopping-leg plant (003): its nominal model, the effects a diagnosis tries, and the
:class:`Plant` record the registry holds."""
from __future__ import annotations

from ...registry import Plant, lazy_hook
from . import effects, topics
from .dataset import check_bag, dataset
from .description import parse_section
from .topics import JOINT_STATE


def baseline(description) -> tuple[str, ...]:
    """Nominal model: the leg's inertia with stance and flight damping (spec 003 sec. 7)."""
    return effects.BASELINE


def candidates(description) -> tuple[str, ...]:
    """Effects a leg diagnosis tries (spec 003 sec. 7)."""
    return effects.BASELINE + effects.CANDIDATES


PLANT = Plant(
    name="leg",
    topics=((topics.JOINT_STATES, JOINT_STATE),),
    dataset=dataset,
    baseline=baseline,
    candidates=candidates,
    parse_section=parse_section,
    contract_topics=topics.TYPES,              # CONTRACT sec. 2, spec 003_leg.md sec. 5
    joint_topic=topics.JOINT_STATES,
    joints=("body", "motor"),
    checked_topics=(topics.CONTACT,),
    check_bag=check_bag,
    channels=("body",),
    topic_names=lambda desc: {topics.JOINT_STATES: ["body", "motor"], topics.CONTACT: ["contact"],
                              **{t: ["height", "phase", "apex_height", "grf"] for t in
                                 (topics.HOP_ESTIMATE, topics.GROUND_TRUTH)}},
    markers=lazy_hook(f"{__package__}.markers", "bag_markers"),
)
