"""A toy plant written in one folder: a damped pendulum driven at its hinge.

It proves that adding a plant touches one place: this package is found through the
``cablelab.plants`` entry-point group (the test writes the entry point), and then the
description loader, ``cable_sim_node --plant pendulum``, ``cablelab record --plant pendulum``,
``diagnose`` and ``report`` all work with no edit anywhere else.

Inverse model on the axis pattern: ``tau = I qdd + m l g sin(q) (+ friction, offset ...)``, one
channel (the hinge torque), one actuator; the generic friction, offset and delay effects apply
because the plant declares the capability ``joint_actuators``.
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from cablelab.conditioning import condition_motion
from cablelab.dataset import Dataset
from cablelab.fields import check_keys, mapping, number
from cablelab.effects import register
from cablelab.effects.base import Effect, Param
from cablelab.errors import CablelabError
from cablelab.plant_interface import DatasetOptions
from cablelab.registry import Plant, register_plant

TOPIC = "/pendulum/joint_states"
JOINT_STATE = "sensor_msgs/msg/JointState"


@dataclass(frozen=True)
class PendulumDescription:
    """``pendulum:`` section: bob mass (kg), rod length (m)."""

    mass: float
    length: float


def parse_section(obj) -> PendulumDescription:
    obj = mapping(obj, "pendulum")
    check_keys(obj, "pendulum", ("mass", "length"), ())
    return PendulumDescription(number(obj, "mass", "pendulum", positive=True),
                               number(obj, "length", "pendulum", positive=True))


def dataset(bag, description, options: DatasetOptions) -> Dataset:
    bag.require(TOPIC, JOINT_STATE)
    js = bag.joint_state(TOPIC)
    if js.names != ["hinge"]:
        raise CablelabError(f"{bag.path}: {TOPIC} has joints {js.names}; expected ['hinge']")
    c = condition_motion(js.t, js.position[:, 0], js.effort[:, 0], options.conditioning, revolute=True,
                         qd=js.velocity[:, 0], source=str(bag.path))
    qd = c["qd"].reshape(-1)
    return Dataset(plant="pendulum", t=c["t"], y=c["effort"].reshape(-1, 1), channels=("hinge",),
                   units=("N m",), signals={"q": c["q"].reshape(-1), "qdd": c["qdd"].reshape(-1)},
                   actuators=("hinge",), act_vel=qd[:, None], act_units=(("N m", "rad"),),
                   inputs={"velocity": qd}, description=description, source=str(bag.path))


register(Effect(
    id="pendulum_inertia", plants=("pendulum",),
    params=(Param("I", "kg m^2", 0.0, 0.0, np.inf, "inertia about the hinge"),),
    explanation="torque to accelerate the bob about the hinge (I qdd)",
    signature="residual follows the acceleration", reference="toy plant (test)",
    regressor=lambda ds: ds.require_signal("qdd").reshape(ds.n, 1, 1)))
register(Effect(
    id="pendulum_gravity", plants=("pendulum",),
    params=(Param("ml", "kg m", 0.0, -np.inf, np.inf, "gravity moment m l"),),
    explanation="gravity pulls the bob down with torque m l g sin(q)",
    signature="residual follows sin(q)", reference="toy plant (test)",
    regressor=lambda ds: (ds.gravity * np.sin(ds.require_signal("q"))).reshape(ds.n, 1, 1)))

PLANT = register_plant(Plant(
    name="pendulum",
    topics=((TOPIC, JOINT_STATE),),
    dataset=dataset,
    baseline=lambda desc: ("pendulum_inertia", "pendulum_gravity"),
    candidates=lambda desc: ("joint_viscous_friction", "joint_coulomb_friction",
                             "torque_sensor_offset"),
    parse_section=parse_section,
    contract_topics={TOPIC: JOINT_STATE},
    joint_topic=TOPIC,
    joints=("hinge",),
    capabilities=frozenset({"joint_actuators"}),
))
