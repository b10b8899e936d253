"""The ``mjcf`` plant: any machine described by a MuJoCo model (MJCF or URDF) and a bag of it.

The nominal model is MuJoCo's inverse dynamics of the given model (:mod:`.dataset`); the
candidates are the effects of :mod:`.effects` plus the generic joint friction, sensor offset and
time delay on the model's joints.
"""
from __future__ import annotations

from ...registry import Plant, lazy_hook
from .dataset import dataset
from .description import dump_section, parse_section
from .topics import TOPICS, contract_topics, topic


def baseline(description) -> tuple[str, ...]:
    """Nominal model: the given MuJoCo model's own inverse dynamics, no added effect."""
    return ()


def candidates(description) -> tuple[str, ...]:
    """Effects a diagnosis tries: the mjcf effects (``payload_mass`` when the description names
    a ``payload_body``, ``tendon_elasticity`` when it names measured ``tendons``: it needs their
    lengths in the bag, and says so when they are absent) and the generic joint ones. ``link_inertia`` is not among them: it holds
    every rigid-body change (a payload is a change of its body's inertia) and would tie with the
    more specific effects; fit it with ``identify --effects link_inertia``."""
    sec = getattr(description, "mjcf", None) if description is not None else None
    cands = ("joint_viscous_friction", "joint_coulomb_friction", "joint_armature", "joint_spring",
             "actuator_gain", "torque_sensor_offset", "time_delay")
    if sec is not None and sec.payload_body:
        cands = ("payload_mass",) + cands
    if sec is not None and sec.tendons:
        cands = cands + ("tendon_elasticity",)
    return cands


#: the joints of the machine without a description: the shipped example arm
#: (``examples/arm3.xml``, what ``cable_sim_node --plant mjcf`` runs by default; default layouts)
EXAMPLE_JOINTS = ("base_yaw", "shoulder", "elbow")


def _topic_names(desc) -> dict:
    sec = getattr(desc, "mjcf", None) if desc is not None else None
    if sec is None:
        return {topic(None, "joint_states"): list(EXAMPLE_JOINTS),
                topic(None, "ground_truth_joint_states"): list(EXAMPLE_JOINTS)}
    from .mjcf import dof_joints

    joints = dof_joints(sec.compiled())
    out = {topic(sec, "joint_states"): joints, topic(sec, "ground_truth_joint_states"): joints}
    if sec.tendons:
        out[topic(sec, "cable_tensions")] = list(sec.tendons)
    return out


PLANT = Plant(
    name="mjcf",
    topics=(),                      # the joint-state topic depends on the description (remapping)
    checked_topics=(TOPICS["joint_states"][0], TOPICS["cable_tensions"][0]),
    dataset=dataset,
    baseline=baseline,
    candidates=candidates,
    parse_section=parse_section,
    dump_section=dump_section,
    contract_topics=contract_topics(),
    joint_topic=TOPICS["joint_states"][0],
    joints=None,
    capabilities=frozenset({"joint_actuators"}),
    topic_names=_topic_names,
    channels=EXAMPLE_JOINTS,
    markers=lazy_hook(f"{__package__}.markers", "bag_markers"),
)
