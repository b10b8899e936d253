"""The suspended CDPR plant: its nominal model, the effects a diagnosis tries, and the
:class:`Plant` record the registry holds (001).

Geometry, estimation, control and trajectory live in the modules next to this one
(:mod:`.geometry`, :mod:`.estimation`, :mod:`.control`, :mod:`.trajectory`); :mod:`.dataset` reads
a bag into the workbench dataset, :mod:`.estimate` runs the offline estimate (``cablelab
estimate``), :mod:`.options` holds the plant's own options (``--tensions``, ``--pose``).
"""
from __future__ import annotations

from ...registry import Plant, lazy_hook
from . import topics
from .dataset import CHANNELS, check_bag, dataset, remeasure
from .topics import (CABLE_TENSIONS as TENSIONS, JOINT_STATE, JOINT_STATES as JOINTS,
                     PLATFORM_POSE as POSE)
from .description import dump_section, parse_section
from .estimate import estimate_bag
from .options import CdprOptions


def baseline(description) -> tuple[str, ...]:
    """Nominal model: the payload's weight (001 eq. 13) with the wrench matrix of Model II when the
    description gives a pulley radius, else Model I (point exits)."""
    c = description.cdpr if description is not None else None
    if c is not None and c.pulley_radius > 0:
        return ("cdpr_gravity", "pulley_geometry")
    return ("cdpr_gravity",)


def candidates(description) -> tuple[str, ...]:
    """Effects a diagnosis tries (the friction and offset ones only matter for the tension source
    that carries them; an effect without signal is simply not significant)."""
    return ("pulley_geometry", "platform_inertia", "winch_coulomb_friction",
            "winch_viscous_friction", "tension_sensor_offset", "time_delay")


PLANT = Plant(
    name="cdpr",
    topics=((JOINTS, JOINT_STATE),),
    dataset=dataset,
    baseline=baseline,
    candidates=candidates,
    remeasure=remeasure,
    parse_section=parse_section,
    dump_section=dump_section,
    contract_topics=topics.TYPES,
    joint_topic=JOINTS,
    joints=tuple(f"winch_{i}" for i in range(1, 9)),
    capabilities=frozenset({"winch_actuators"}),
    estimate=estimate_bag,
    checked_topics=(TENSIONS, topics.REFERENCE, POSE),
    check_bag=check_bag,
    channels=CHANNELS,
    topic_names=lambda desc: _topic_names(desc),
    markers=lazy_hook(f"{__package__}.markers", "bag_markers"),
    options_type=CdprOptions,
)


def _topic_names(desc) -> dict:
    """Element names of the CDPR JointState topics (CONTRACT sec. 2) for ``desc``'s cables."""
    n = len(desc.cdpr.cables) if desc is not None and desc.cdpr is not None else 8
    return {JOINTS: [f"winch_{i}" for i in range(1, n + 1)],
            TENSIONS: [f"cable_{i}" for i in range(1, n + 1)]}
