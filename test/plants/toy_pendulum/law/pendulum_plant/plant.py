"""The ``pendulum`` plant as the workbench sees it: :data:`PLANT`, its hooks (dataset, nominal
model, candidate effects, description section) and what a recording of it holds. Registered by
the package's ``__init__.py``."""
from __future__ import annotations

from cablelab.registry import Plant

from . import topics
from .dataset import dataset
from .description import dump_section, parse_section
from .mjcf import JOINT


def baseline(description) -> tuple[str, ...]:
    """Effect ids of the nominal model (:mod:`.effects`)."""
    return ("pendulum_inertia", "pendulum_gravity")


def candidates(description) -> tuple[str, ...]:
    """Effect ids ``diagnose`` may add; the generic joint effects apply because the plant declares
    the capability ``joint_actuators``."""
    return ("joint_viscous_friction", "joint_coulomb_friction", "torque_sensor_offset")


PLANT = Plant(
    name="pendulum",
    topics=((topics.JOINT_STATES, topics.JOINT_STATE),),
    dataset=dataset,
    baseline=baseline,
    candidates=candidates,
    parse_section=parse_section,
    dump_section=dump_section,
    contract_topics=topics.TYPES,
    joint_topic=topics.JOINT_STATES,
    joints=(JOINT,),
    capabilities=frozenset({"joint_actuators"}),
    channels=(JOINT,),
)
