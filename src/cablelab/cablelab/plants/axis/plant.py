"""The single-axis plant: its nominal model, the effects a diagnosis tries, and the :class:`Plant`
record the registry holds (CONTRACT sections 2-3, ``/axis/joint_states``).

The nominal model is inertia + viscous friction (+ gravity when the description gives
``gravity_moment``); Coulomb friction, sensor offset and time delay are the candidates a diagnosis
tries.
"""
from __future__ import annotations

from ...registry import Plant, lazy_hook
from . import topics
from .dataset import JOINT_STATE, TOPIC, dataset
from .description import parse_section
from .freerun import fit_free_run, free_run_compare


def baseline(description) -> tuple[str, ...]:
    """Nominal model: inertia + viscous friction (+ gravity for a revolute load with a known
    gravity moment)."""
    base = ("axis_inertia", "joint_viscous_friction")
    ax = description.axis if description is not None else None
    if ax is not None and ax.joint_type == "revolute" and ax.gravity_moment:
        base += ("axis_gravity",)
    return base


def candidates(description) -> tuple[str, ...]:
    """Effects a diagnosis tries on the axis."""
    cands = ("axis_inertia", "joint_viscous_friction", "joint_coulomb_friction",
             "torque_sensor_offset", "time_delay")
    ax = description.axis if description is not None else None
    if ax is not None and ax.joint_type == "revolute":
        cands += ("axis_gravity",)
    return cands


PLANT = Plant(
    name="axis",
    topics=((TOPIC, JOINT_STATE),),
    dataset=dataset,
    baseline=baseline,
    candidates=candidates,
    simulate=free_run_compare,
    simulation_fit=fit_free_run,
    parse_section=parse_section,
    contract_topics=topics.TYPES,
    joint_topic=TOPIC,
    joints=("joint",),
    capabilities=frozenset({"joint_actuators"}),
    channels=("joint",),
    topic_names=lambda desc: {TOPIC: ["joint"], topics.GROUND_TRUTH: ["joint"]},
    markers=lazy_hook(f"{__package__}.markers", "bag_markers"),
)
