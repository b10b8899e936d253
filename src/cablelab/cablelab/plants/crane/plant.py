"""The boom-crane plant (002; CONTRACT sections 2-3, prefix ``/crane``): its nominal model, the
effects a diagnosis tries, and the :class:`Plant` record the registry holds.

Modules next to this one: :mod:`.kinematics` (boom tip, payload, exact swing angles),
:mod:`.symbolic` -> :mod:`.dynamics_generated` (regressor Y(q, qd, qdd) of 002 eq. A.3-A.4),
:mod:`.model` (:class:`CraneParams`, M, G, inverse dynamics), :mod:`.identify` (base parameters),
:mod:`.swing` (swing estimation), :mod:`.control` (PD + gravity compensation),
:mod:`.freerun` (free-run comparison), :mod:`.dataset` (bag -> Dataset), :mod:`.estimate`
(``cablelab estimate``), :mod:`.excite` (experiment design), :mod:`.effects`, :mod:`.mjcf` and
:mod:`.sim` (the MuJoCo crane).
"""
from __future__ import annotations

from ...registry import Plant, lazy_hook
from . import topics
from .dataset import JOINTS, check_bag, dataset
from .topics import JOINT_STATE, JOINT_STATES, PAYLOAD_POSE, POSE, TIP_POSE
from .description import parse_section
from .estimate import estimate_bag
from .freerun import fit_free_run, free_run_compare
from .options import CraneOptions


def baseline(description) -> tuple[str, ...]:
    """Nominal model: the rigid body (+ the counterbalance when the description knows one)."""
    c = description.crane if description is not None else None
    if c is not None and c.counterbalance is not None:
        return ("crane_rigid_body", "counterbalance")
    return ("crane_rigid_body",)


def candidates(description) -> tuple[str, ...]:
    """Effects a crane diagnosis tries (CONTRACT sec. 4)."""
    return ("counterbalance", "base_tilt", "joint_viscous_friction", "joint_coulomb_friction",
            "torque_sensor_offset", "time_delay")


PLANT = Plant(
    name="crane",
    topics=((JOINT_STATES, JOINT_STATE), (TIP_POSE, POSE), (PAYLOAD_POSE, POSE)),
    dataset=dataset,
    baseline=baseline,
    candidates=candidates,
    simulate=free_run_compare,
    simulation_fit=fit_free_run,
    parse_section=parse_section,
    contract_topics=topics.TYPES,
    joint_topic=JOINT_STATES,
    joints=JOINTS,
    capabilities=frozenset({"joint_actuators"}),
    estimate=estimate_bag,
    check_bag=check_bag,
    options_type=CraneOptions,
    channels=JOINTS,
    markers=lazy_hook(f"{__package__}.markers", "bag_markers"),
    topic_names=lambda desc: {JOINT_STATES: list(JOINTS), **{t: ["theta1", "theta2", "rope_length"] for t in
                                                          (topics.SWING_ESTIMATE, topics.SWING_TRUTH)}},
)
