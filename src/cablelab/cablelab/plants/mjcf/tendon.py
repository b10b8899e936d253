"""Cable stretch of the measured tendons (``tendon_elasticity``) and the cable-length channels it
acts on.

With the joints measured directly, a stretching cable does not show in the force channels (its
tension is the same all along it, measured or not). It shows against the cable's length as the
winch encoder reads it (``cable_tensions`` ``position``, CONTRACT): the winch pays out the cable's
rest length, which is shorter than the path the cable spans by its stretch. For a cable of
stiffness k under tension T,

    L_meas = L(q) - T / k + b

with ``L(q)`` the rigid tendon length MuJoCo computes at the measured joint positions
(``ten_length``, spatial tendons over their wrapping geometry) and ``b`` the encoder's zero. A bag
whose ``cable_tensions`` carry positions adds one channel per such tendon (``<tendon> length``,
m): measured ``L_meas``, nominal ``L(q) + b0`` with ``b0`` the record's median of
``L_meas - L(q)`` (the encoder's zero is not part of the model; it is referenced once, so a
rigid cable leaves no residual). The effect's columns per tendon are ``-T`` (its compliance
1/k, m/N) and ``1`` (a correction of the zero, m); it reports the stiffness k (N/m), the axial
stiffness EA = k L (N) at the record's mean rigid length, and the zero b (m). MuJoCo's own
elastic cable (a tendon actuator with ``kp = k``, or tendon ``stiffness``) has this k.
"""
from __future__ import annotations

import numpy as np

from ...dataset import Dataset
from ...effects import register
from ...effects.base import Effect, Param, Physical
from ...errors import CablelabError
from ...model import KNOWN_OUTPUT

#: ``Dataset.signals`` keys: the tendons with a length channel (in channel order after the
#: joints), their rigid lengths (N, k), the encoder zeros b0 (k,) and the number of joint channels
LENGTH_TENDONS, RIGID_LENGTH, LENGTH_ZERO, JOINT_CHANNELS = (
    "length_tendons", "rigid_length", "length_zero", "joint_channels")
#: name of a tendon's length channel
LENGTH_CHANNEL = "{} length"


def with_length_channels(ds: Dataset, tendons, measured: np.ndarray, rigid: np.ndarray) -> Dataset:
    """The dataset with one length channel per tendon after its joint channels.

    Args:
        ds: the mjcf dataset of the joint channels (its ``tension`` signal holds the measured
            tensions of the section's tendons, in the section's order).
        tendons: names of the tendons whose length is measured.
        measured: (N, k) their lengths as the winch encoders read them, m (conditioned like the
            efforts); rigid: (N, k) MuJoCo's ``ten_length`` at the conditioned joint positions.
    """
    measured = np.asarray(measured, float).reshape(ds.n, -1)
    rigid = np.asarray(rigid, float).reshape(ds.n, -1)
    nj, k = ds.n_channels, measured.shape[1]
    zero = np.median(measured - rigid, axis=0)
    signals = {**ds.signals, KNOWN_OUTPUT: np.hstack([ds.signals[KNOWN_OUTPUT], rigid + zero]),
               LENGTH_TENDONS: tuple(tendons), RIGID_LENGTH: rigid, LENGTH_ZERO: zero,
               JOINT_CHANNELS: nj}
    act_map = None
    if ds.act_vel is not None:  # the joint actuators act on the joint channels only
        n_act = ds.act_vel.shape[1]
        act_map = np.zeros((ds.n, nj + k, n_act))
        act_map[:, np.arange(n_act), np.arange(n_act)] = 1.0
    return ds.replace(y=np.hstack([ds.y, measured]),
                      channels=tuple(ds.channels) + tuple(LENGTH_CHANNEL.format(x) for x in tendons),
                      units=tuple(ds.units) + ("m",) * k, signals=signals, act_map=act_map)


def on_joint_channels(ds: Dataset, block: np.ndarray) -> np.ndarray:
    """(N, C, p) block of a term written on the joint channels (N, n_joints, p): zero on the
    length channels (a rigid-body term does not change a cable's length reading)."""
    block = np.asarray(block, float)
    extra = ds.n_channels - block.shape[1]
    if extra <= 0:
        return block
    return np.concatenate([block, np.zeros((block.shape[0], extra) + block.shape[2:])], axis=1)


def joint_part(ds: Dataset, x: np.ndarray) -> np.ndarray:
    """The joint channels' columns of an (N, C) array of the dataset."""
    return np.asarray(x)[:, : int(ds.signals.get(JOINT_CHANNELS, ds.n_channels))]


def _tendon_names(ds: Dataset) -> list[str]:
    """The tendons with a length channel; ``["tendon"]`` (the naming template) for a dataset
    without an ``mjcf`` description; none for an mjcf dataset without lengths."""
    if LENGTH_TENDONS in ds.signals:
        return list(ds.signals[LENGTH_TENDONS])
    return ["tendon"] if getattr(ds.description, "mjcf", None) is None else []


def _regressor(ds: Dataset) -> np.ndarray:
    """Per tendon: ``-T`` on its length channel (compliance) and 1 (zero correction); a one-line
    error for a dataset without lengths."""
    names = _tendon_names(ds)
    if LENGTH_TENDONS not in ds.signals:
        raise CablelabError(
            f"effect tendon_elasticity: {ds.source or 'the dataset'} has no cable lengths: cable "
            "stretch shows against the lengths the winch encoders measure (cable_tensions "
            "position of the description's tendons)")
    sec_tendons = list(ds.description.mjcf.tendons)
    tension = ds.require_signal("tension")[:, [sec_tendons.index(x) for x in names]]
    nj, k = int(ds.signals[JOINT_CHANNELS]), len(names)
    out = np.zeros((ds.n, ds.n_channels, 2 * k))
    idx = np.arange(k)
    out[:, nj + idx, idx] = -tension
    out[:, nj + idx, k + idx] = 1.0
    return out


class TendonElasticityEffect(Effect):
    """``tendon_elasticity``: two parameters per tendon with a length channel (the names depend
    on the model, so :meth:`columns` expands them per tendon)."""

    def columns(self, ds: Dataset) -> list[Param]:
        names = _tendon_names(ds)
        return ([Param(f"c[{x}]", "m/N", 0.0, 0.0, np.inf, f"compliance 1/k of {x}") for x in names]
                + [Param(f"db[{x}]", "m", 0.0, -np.inf, np.inf,
                         f"correction of {x}'s length-encoder zero") for x in names])


def _physical(ds: Dataset):
    names = _tendon_names(ds)
    rigid = ds.signals.get(RIGID_LENGTH)
    mean_len = (np.nanmean(rigid, axis=0) if rigid is not None else np.full(len(names), np.nan))
    zero = np.asarray(ds.signals.get(LENGTH_ZERO, np.zeros(len(names))), float)

    def k_of(p, x):
        c = p[f"c[{x}]"]
        return 1.0 / c if c > 0 else float("nan")

    out = [Physical(f"k[{x}]", "N/m", lambda p, x=x: k_of(p, x),
                    "cable stiffness: tension / stretch (MuJoCo tendon actuator kp or stiffness)")
           for x in names]
    out += [Physical(f"EA[{x}]", "N", lambda p, x=x, L=float(mean_len[i]): k_of(p, x) * L,
                     "axial stiffness k L at the record's mean rigid cable length")
            for i, x in enumerate(names)]
    out += [Physical(f"zero[{x}]", "m", lambda p, x=x, b=float(zero[i]): b + p[f"db[{x}]"],
                     "length encoder reading minus the rigid cable length at zero tension")
            for i, x in enumerate(names)]
    return tuple(out)


TENDON_ELASTICITY = register(TendonElasticityEffect(
    id="tendon_elasticity",
    plants=("mjcf",),
    params=(),
    explanation="the cables stretch under tension: the winch pays out less than the path they span",
    signature="measured cable length falls short of the rigid length in proportion to the tension",
    reference="CONTRACT sec. 4 (mjcf); L_meas = ten_length(q) - T / k + b, MuJoCo tendon "
              "actuator kp / tendon stiffness",
    regressor=_regressor,
    physical=_physical,
))
