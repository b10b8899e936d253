"""Bag -> :class:`cablelab.dataset.Dataset`: the hinge's conditioned motion and torque, the
output channel the effects' regressors explain (``tau``, N m)."""
from __future__ import annotations

from cablelab.conditioning import condition_motion
from cablelab.dataset import Dataset
from cablelab.errors import CablelabError
from cablelab.plant_interface import DatasetOptions

from . import topics
from .mjcf import JOINT


def dataset(bag, description, options: DatasetOptions) -> Dataset:
    """The dataset of a recording (``options``: conditioning and the plant's own options)."""
    bag.require(topics.JOINT_STATES, topics.JOINT_STATE)
    js = bag.joint_state(topics.JOINT_STATES)
    if js.names != [JOINT]:
        raise CablelabError(f"{bag.path}: {topics.JOINT_STATES} has joints {js.names}; expected [{JOINT!r}]")
    c = condition_motion(js.t, js.position[:, 0], js.effort[:, 0], options.conditioning, revolute=True,
                         qd=js.velocity[:, 0], source=str(bag.path))
    qd = c["qd"].reshape(-1)
    return Dataset(plant="pendulum", t=c["t"], y=c["effort"].reshape(-1, 1), channels=(JOINT,),
                   units=("N m",), signals={"q": c["q"].reshape(-1), "qdd": c["qdd"].reshape(-1)},
                   actuators=(JOINT,), act_vel=qd[:, None], act_units=(("N m", "rad"),),
                   inputs={"velocity": qd}, description=description, source=str(bag.path))
