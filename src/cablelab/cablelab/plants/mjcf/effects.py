"""Effects of the ``mjcf`` plant (CONTRACT section 4). Their columns come from the MuJoCo model
through the dataset (:mod:`.dataset`, :mod:`.inverse`), none is an equation written for one
machine. The generic joint friction, sensor offset and time delay apply through the
``joint_actuators`` capability (one actuator per joint of the model). ``tendon_elasticity`` acts on
the cable-length channels and lives with them in :mod:`.tendon`; the rigid-body columns here are
zero on those channels (:func:`.tendon.on_joint_channels`).
"""
from __future__ import annotations

import numpy as np

from ...effects import register
from ...effects.base import Physical
from ...errors import CablelabError
from ...dataset import Dataset
from ...effects.base import Effect, Param
from ...model import KNOWN_OUTPUT
from . import tendon  # noqa: F401  (registers tendon_elasticity)
from .tendon import joint_part, on_joint_channels


def _payload(ds: Dataset) -> np.ndarray:
    cols = ds.signals.get("payload_columns")
    if cols is None:
        raise CablelabError("effect payload_mass: the description names no mjcf.payload_body")
    return on_joint_channels(ds, cols)


def _payload_physical(ds: Dataset):
    c0 = np.asarray(ds.signals.get("payload_com0", np.zeros(3)), float)

    def com(k):
        name = "mc" + "xyz"[k]
        return lambda p: c0[k] + p[name] / p["m"] if p["m"] else float("nan")

    return (Physical("m", "kg", lambda p: p["m"], "payload mass added to payload_body"),
            *(Physical("com_" + "xyz"[k], "m", com(k), "payload centre of mass, payload_body frame")
              for k in range(3)))


PAYLOAD_MASS = register(Effect(
    id="payload_mass",
    plants=("mjcf",),
    params=(Param("m", "kg", 0.0, -np.inf, np.inf, "mass added to payload_body"),
            Param("mcx", "kg m", 0.0, -np.inf, np.inf, "its first moment about the body's centre of mass, x"),
            Param("mcy", "kg m", 0.0, -np.inf, np.inf, "its first moment about the body's centre of mass, y"),
            Param("mcz", "kg m", 0.0, -np.inf, np.inf, "its first moment about the body's centre of mass, z")),
    explanation="an unknown payload on payload_body: the arm carries more mass than its model",
    signature="residual follows the gravity and inertia load of the payload body",
    reference="CONTRACT sec. 4 (mjcf); columns: MuJoCo's Newton-Euler terms (cdof, cvel, cacc) per "
              "standard inertial parameter of the body, equal to mj_inverse differences",
    regressor=_payload,
    physical=_payload_physical,
))


def _per_joint(signal: str):
    return lambda ds: ds.actuator_block(ds.require_signal(signal))


JOINT_ARMATURE = register(Effect(
    id="joint_armature",
    plants=("mjcf",),
    params=(Param("armature", "{inertia}", 0.0, -np.inf, np.inf,
                  "reflected rotor inertia beyond the model's (MuJoCo armature)"),),
    explanation="the rotor's reflected inertia adds armature x qdd at its joint",
    signature="residual follows each joint's own acceleration",
    reference="CONTRACT sec. 4 (mjcf); MuJoCo joint armature",
    regressor=_per_joint("qdd"),
    per_actuator=True,
))


def _spring(ds: Dataset) -> np.ndarray:
    q = ds.require_signal("q")
    return np.concatenate([ds.actuator_block(q), ds.actuator_block(-np.ones_like(q))], axis=2)


def _spring_physical(ds: Dataset):
    out = []
    for i, j in enumerate(ds.actuators):
        s = f"[{j}]" if len(ds.actuators) > 1 else ""
        eu, pu = ds.act_units[i] if i < len(ds.act_units) else ("N m", "rad")
        out.append(Physical("k" + s, f"{eu}/{pu}", lambda p, s=s: p["k" + s], "joint spring stiffness"))
        out.append(Physical("q0" + s, pu, lambda p, s=s: p["kq0" + s] / p["k" + s] if p["k" + s]
                            else float("nan"), "joint spring rest position"))
    return tuple(out)


JOINT_SPRING = register(Effect(
    id="joint_spring",
    plants=("mjcf",),
    params=(Param("k", "{effort}/{position}", 0.0, -np.inf, np.inf, "joint stiffness"),
            Param("kq0", "{effort}", 0.0, -np.inf, np.inf, "stiffness x rest position")),
    explanation="a spring at the joint (gravity compensator, cable chain, harmonic drive) "
                "pulls it towards a rest position",
    signature="residual follows the joint position",
    reference="CONTRACT sec. 4 (mjcf); MuJoCo joint stiffness / springref",
    regressor=_spring,
    per_actuator=True,
    physical=_spring_physical,
))


def _gain(ds: Dataset) -> np.ndarray:
    """The nominal force on each joint whose effort is measured (a joint without an effort
    sensor has no torque constant: its column is zero, the gain is not excited)."""
    nominal = joint_part(ds, ds.require_signal(KNOWN_OUTPUT))
    driven = np.asarray(ds.signals.get("driven", np.ones(nominal.shape[1], bool)), bool)
    return ds.actuator_block(nominal * driven[None, :])


def _gain_physical(ds: Dataset):
    out = []
    for j in ds.actuators:
        s = f"[{j}]" if len(ds.actuators) > 1 else ""
        out.append(Physical("gain" + s, "1", lambda p, s=s: 1.0 + p["dgain" + s],
                            "measured effort / applied generalised force"))
    return tuple(out)


ACTUATOR_GAIN = register(Effect(
    id="actuator_gain",
    plants=("mjcf",),
    params=(Param("dgain", "1", 0.0, -np.inf, np.inf, "gain - 1 of the measured effort"),),
    explanation="the measured effort is the applied force times a gain (torque-constant error)",
    signature="residual is proportional to the model's own joint force",
    reference="CONTRACT sec. 4 (mjcf)",
    regressor=_gain,
    per_actuator=True,
    physical=_gain_physical,
))


# ----------------------------------------------------------------------------- link inertia
#: ``Dataset.signals`` keys of the link-inertia columns (computed on first use) and body names
LINK_COLUMNS, LINK_BODIES = "link_inertia_columns", "link_bodies"


def _moving_bodies(model) -> list[int]:
    """Bodies that move with some joint (not welded to the world), in tree order."""
    return [b for b in range(1, model.nbody) if model.body_weldid[b] != 0]


def _link_columns(ds: Dataset) -> np.ndarray:
    """(N, C, 10 n_bodies) columns of every moving body's standard inertial parameters
    (:func:`.inverse.body_columns`), computed once per dataset from its q, qd, qdd (one inverse
    dynamics pass for all bodies)."""
    if LINK_COLUMNS not in ds.signals:
        from .description import section_of
        from .inverse import body_columns, inverse_record

        model = section_of(ds.description).compiled(ds.gravity)
        q, qd, qdd = (ds.require_signal(k) for k in ("q", "qd", "qdd"))
        rec = inverse_record(model, q, qd, qdd)
        ds.signals[LINK_COLUMNS] = np.concatenate(
            [body_columns(model, rec, b) for b in _moving_bodies(model)], axis=2)
    return on_joint_channels(ds, ds.signals[LINK_COLUMNS])


def _link_names(ds: Dataset) -> list[str]:
    """The moving bodies' names; ``["body"]`` (the naming template) for a dataset without an
    ``mjcf`` description."""
    if getattr(ds.description, "mjcf", None) is None and LINK_BODIES not in ds.signals:
        return ["body"]
    if LINK_BODIES not in ds.signals:
        from .description import section_of
        from .mjcf import names

        model = section_of(ds.description).compiled()
        body = names(model, "body")
        ds.signals[LINK_BODIES] = [body[b] for b in _moving_bodies(model)]
    return ds.signals[LINK_BODIES]


class LinkInertiaEffect(Effect):
    """``link_inertia``: its parameters are the ten standard parameters of each moving body of
    the model (the names depend on the model, so :meth:`columns` expands them per body)."""

    def columns(self, ds: Dataset) -> list[Param]:
        from .inverse import STANDARD_PARAMS

        units = {"m": "kg", "h": "kg m", "I": "kg m^2"}
        return [Param(f"d{p}[{b}]", units[p[0]], 0.0, -np.inf, np.inf,
                      f"change of {b}'s standard inertial parameter {p}")
                for b in _link_names(ds) for p in STANDARD_PARAMS]


LINK_INERTIA = register(LinkInertiaEffect(
    id="link_inertia",
    plants=("mjcf",),
    params=(),
    explanation="the links' masses, centres of mass and inertias differ from the model",
    signature="residual follows the rigid-body dynamics (gravity and inertia loads) of the links",
    reference="CONTRACT sec. 4 (mjcf); standard inertial parameters, base parameters by the held "
              "(unidentifiable) directions of the fit",
    regressor=_link_columns,
))
