"""The data every model and effect is written against: :class:`Dataset`, conditioned
measurements of one plant as numpy arrays over time (SI units).

The measured output channels ``y`` (N, C) the model predicts (axis: the drive force; crane:
slew/luff torque and hoist force; CDPR: the wrench balance or tensions), the plant's own signals
(``q``, ``qd``, ``qdd``, ...), and the actuator view used by the generic per-actuator effects:
actuator velocities ``act_vel`` (N, n_act) and the actuator -> channel map ``act_map``
(N, C, n_act) (``None`` = identity, one channel per actuator).
"""
from __future__ import annotations

import dataclasses
from dataclasses import dataclass, field

import numpy as np

from .errors import CablelabError

#: gravity of a dataset without a description, m/s^2
STANDARD_GRAVITY = 9.81


@dataclass
class Dataset:
    """Conditioned measurements of one plant, numpy arrays over N time samples (SI units).

    Args:
        plant: plant name (``axis``, ``crane``, ``cdpr``, ...).
        t: (N,) sample times, s (uniform after conditioning).
        y: (N, C) measured output channels the model predicts.
        channels: C channel names; ``units`` their units.
        signals: plant-specific conditioned signals by name, each (N,) or (N, k) or (N, ...).
        actuators: names of the actuators (one per column of ``act_vel``).
        act_vel: (N, n_act) actuator velocities (rad/s or m/s), for friction effects.
        act_map: (N, C, n_act) map from an actuator-level force/torque to the output channels;
            ``None`` means identity (C == n_act, channel i is actuator i).
        act_units: per actuator ``(effort unit, position unit)``, e.g. ``("N m", "rad")``; fills
            the ``{effort}`` / ``{position}`` placeholders of effect parameter units.
        valid: (N,) bool, samples usable in a fit (False at borders, after a delay shift, ...).
        regimes: name -> (N,) label array (str) for residual-by-regime analysis (plant extras;
            velocity/acceleration regimes are derived from ``act_vel`` by the diagnosis).
        inputs: name -> (N,) input signals for residual cross-correlation (e.g. velocity).
        description: the plant :class:`~cablelab.description.Description`.
        source: where the data came from (bag path), for messages.
        parallel_hz: cut-off (Hz) of the parallel filter (:mod:`cablelab.parallel_filter`):
            ``y`` is low-passed with it and every regressor column is filtered the same way by
            :meth:`cablelab.model.Model.regressor`; ``None`` = no parallel filter.
        noise_map: (N, C, S) map from S independently noisy sensors to the channels
            (``y_n = noise_map[n] @ readings_n``, e.g. a wrench from cable tensions); the fit then
            whitens each sample with the sensors' estimated noise (:mod:`cablelab.fit.noise`).
            ``None``: each channel is one sensor (weighted by its own noise level).
    """

    plant: str
    t: np.ndarray
    y: np.ndarray
    channels: tuple[str, ...]
    units: tuple[str, ...] = ()
    signals: dict = field(default_factory=dict)
    actuators: tuple[str, ...] = ()
    act_vel: np.ndarray | None = None
    act_map: np.ndarray | None = None
    act_units: tuple = ()
    valid: np.ndarray | None = None
    regimes: dict = field(default_factory=dict)
    inputs: dict = field(default_factory=dict)
    description: object = None
    source: str = ""
    parallel_hz: float | None = None
    noise_map: np.ndarray | None = None

    def __post_init__(self) -> None:
        self.t = np.asarray(self.t, dtype=float)
        self.y = np.asarray(self.y, dtype=float)
        if self.y.ndim == 1:
            self.y = self.y[:, None]
        n = self.t.shape[0]
        if self.y.shape[0] != n:
            raise CablelabError(f"{self.source or 'dataset'}: y has {self.y.shape[0]} samples, t has {n}")
        if len(self.channels) != self.y.shape[1]:
            raise CablelabError(f"{self.source or 'dataset'}: {len(self.channels)} channel names for "
                                f"{self.y.shape[1]} output columns")
        if not self.units:
            self.units = ("",) * len(self.channels)
        if self.valid is None:
            self.valid = np.ones(n, dtype=bool)
        if self.act_vel is not None:
            self.act_vel = np.asarray(self.act_vel, dtype=float).reshape(n, -1)
            if not self.actuators:
                self.actuators = tuple(self.channels) if self.act_vel.shape[1] == len(self.channels) \
                    else tuple(f"act_{i + 1}" for i in range(self.act_vel.shape[1]))

    # ------------------------------------------------------------------ sizes
    @property
    def n(self) -> int:
        """Number of samples N."""
        return int(self.t.shape[0])

    @property
    def n_channels(self) -> int:
        return int(self.y.shape[1])

    @property
    def dt(self) -> float:
        """Median sample period, s."""
        return float(np.median(np.diff(self.t))) if self.n > 1 else 1.0

    @property
    def fs(self) -> float:
        """Sample rate, Hz."""
        return 1.0 / self.dt

    @property
    def gravity(self) -> float:
        """Gravity g, m/s^2: the description's, else the standard 9.81."""
        return float(getattr(self.description, "gravity", STANDARD_GRAVITY))

    # ------------------------------------------------------------------ helpers for effects
    def actuator_block(self, per_actuator: np.ndarray) -> np.ndarray:
        """(N, C, n_act) regressor block of a per-actuator term.

        ``per_actuator`` (N, n_act) is the term's value per unit parameter at each actuator
        (e.g. ``sign(qd)`` for Coulomb friction); it is mapped to the channels through
        ``act_map`` (identity when ``None``).
        """
        x = np.asarray(per_actuator, dtype=float).reshape(self.n, -1)
        if self.act_map is None:
            if x.shape[1] != self.n_channels:
                raise CablelabError(f"{self.plant}: {x.shape[1]} actuators but {self.n_channels} "
                                    "channels and no act_map")
            out = np.zeros((self.n, self.n_channels, x.shape[1]))
            idx = np.arange(x.shape[1])
            out[:, idx, idx] = x
            return out
        return self.act_map * x[:, None, :]

    def require_signal(self, name: str) -> np.ndarray:
        """A plant signal by name, or a one-line error naming it."""
        if name not in self.signals:
            have = ", ".join(sorted(self.signals)) or "none"
            raise CablelabError(f"{self.plant} dataset has no signal {name!r} (has: {have})")
        return self.signals[name]

    def require_actuators(self, effect_id: str) -> np.ndarray:
        if self.act_vel is None:
            raise CablelabError(f"effect {effect_id}: plant {self.plant} exposes no actuator velocities")
        return self.act_vel

    def subset(self, idx) -> "Dataset":
        """The dataset restricted to sample indices ``idx`` (bool mask or integer array)."""
        idx = np.asarray(idx)
        n = self.n

        def cut(v):
            if isinstance(v, np.ndarray) and v.ndim >= 1 and v.shape[0] == n:
                return v[idx]
            return v

        valid = self.valid[idx]
        if self.parallel_hz:  # the regressor is filtered on the subset: its new edges settle
            from .parallel_filter import edge_mask

            valid = valid & edge_mask(self.t[idx], self.parallel_hz)
        return dataclasses.replace(
            self,
            t=self.t[idx], y=self.y[idx],
            signals={k: cut(v) for k, v in self.signals.items()},
            act_vel=cut(self.act_vel), act_map=cut(self.act_map), valid=valid,
            noise_map=cut(self.noise_map),
            regimes={k: cut(v) for k, v in self.regimes.items()},
            inputs={k: cut(v) for k, v in self.inputs.items()},
        )

    def replace(self, **changes) -> "Dataset":
        return dataclasses.replace(self, **changes)
