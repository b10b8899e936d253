"""The single-axis plant (CONTRACT sections 2-3, ``/axis/joint_states``).

Inverse model (EMPS reference, IDIM):

    force = M qdd + Fv qd + Fc sign(qd) + OF  (+ m c g sin q for a revolute joint, q = 0 down)

one output channel (the measured motor force / torque), one actuator (identity map). The nominal
model is inertia + viscous friction (+ gravity when the description gives ``gravity_moment``);
Coulomb friction, sensor offset and time delay are the candidates a diagnosis tries.
"""
from __future__ import annotations

import numpy as np

from ..conditioning import Conditioning, condition_motion
from ..errors import CablelabError
from ..model import Dataset
from . import Plant, register_plant

TOPIC = "/axis/joint_states"
JOINT_STATE = "sensor_msgs/msg/JointState"


def dataset_from_arrays(t, q, effort, description, options: dict | None = None, *, qd=None,
                        source: str = "data") -> Dataset:
    """Axis dataset from raw arrays.

    Args:
        t: (N,) s; q: (N,) position (m or rad); effort: (N,) force (N) or torque (N m);
        description: :class:`~cablelab.description.Description` with an ``axis`` section.
        options: ``{"conditioning": Conditioning}`` (defaults when absent).
        qd: optional measured velocity (N,); derived from q when None or not finite.
    """
    options = options or {}
    opts = options.get("conditioning") or Conditioning()
    revolute = description.axis is not None and description.axis.joint_type == "revolute"
    c = condition_motion(np.asarray(t, float), np.asarray(q, float), np.asarray(effort, float), opts,
                         revolute=revolute, qd=None if qd is None else np.asarray(qd, float),
                         source=source)
    unit = "N m" if revolute else "N"
    qd_c = c["qd"].reshape(-1)
    return Dataset(
        plant="axis", t=c["t"], y=c["effort"].reshape(-1, 1), channels=("joint",), units=(unit,),
        signals={"q": c["q"].reshape(-1), "qd": qd_c, "qdd": c["qdd"].reshape(-1)},
        actuators=("joint",), act_vel=qd_c[:, None], act_units=((unit, "rad" if revolute else "m"),),
        inputs={"velocity": qd_c, "acceleration": c["qdd"].reshape(-1)},
        regimes={"position": _position_bins(c["q"].reshape(-1))},
        description=description, source=source,
    )


def _position_bins(q: np.ndarray, bins: int = 4) -> np.ndarray:
    edges = np.quantile(q, np.linspace(0, 1, bins + 1)[1:-1])
    idx = np.searchsorted(edges, q)
    lo = np.concatenate([[q.min()], edges])
    hi = np.concatenate([edges, [q.max()]])
    labels = np.array([f"q in [{a:.3g}, {b:.3g}]" for a, b in zip(lo, hi)])
    return labels[idx]


def dataset(bag, description, options: dict | None = None) -> Dataset:
    """Axis dataset from a bag's ``/axis/joint_states`` (joint ``joint`` or the only joint)."""
    bag.require(TOPIC, JOINT_STATE)
    js = bag.joint_state(TOPIC)
    if not js.names:
        raise CablelabError(f"{bag.path}: {TOPIC} has no joint names")
    col = js.names.index("joint") if "joint" in js.names else 0
    if len(js.names) > 1 and "joint" not in js.names:
        raise CablelabError(f"{bag.path}: {TOPIC} has joints {js.names}; expected one named 'joint'")
    q, eff = js.position[:, col], js.effort[:, col]
    for name, arr in (("position", q), ("effort", eff)):
        if not np.isfinite(arr).any():
            raise CablelabError(f"{bag.path}: {TOPIC} has no {name} values")
    qd = js.velocity[:, col]
    return dataset_from_arrays(js.t, q, eff, description, options,
                               qd=qd if np.isfinite(qd).all() else None, source=str(bag.path))


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


AXIS = register_plant(Plant(
    name="axis",
    topics=((TOPIC, JOINT_STATE),),
    dataset=dataset,
    baseline=baseline,
    candidates=candidates,
    channels_doc="joint: measured motor force (N, prismatic) or torque (N m, revolute)",
))
