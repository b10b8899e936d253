"""Models: a plant plus a set of effects plus parameters (issue 3, "Models and effects").

The objects every plant and effect is written against:

* :class:`Param` - one physical parameter: name, SI unit, nominal value, box bounds.
* :class:`Dataset` - conditioned measurements of one plant as numpy arrays over time: the measured
  output channels ``y`` (N, C) the model predicts (axis: the drive force; crane: slew/luff torque
  and hoist force; CDPR: the wrench balance or tensions), the plant's own signals (``q``, ``qd``,
  ``qdd``, ...), and the actuator view used by the generic per-actuator effects: actuator
  velocities ``act_vel`` (N, n_act) and the actuator -> channel map ``act_map`` (N, C, n_act)
  (``None`` = identity, one channel per actuator).
* :class:`Effect` - one physical phenomenon: its parameters and its contribution as a regressor
  column block ``Phi_e(data)`` (N, C, p_e) (model linear in the parameters) and/or a data
  ``transform`` driven by a few nonlinear parameters (e.g. a time delay), searched outside the
  linear least squares (separable least squares).
* :class:`Model` - plant name + effect ids + known (fixed) parameters. Linear in the free
  parameters: ``y = sum_e Phi_e @ theta_e``; fixed parameters are moved to the left-hand side.

The pattern is 002 eq. 4.2 (``tau = Y(q, qd, qdd) pi``) generalised to any set of effects.
"""
from __future__ import annotations

import dataclasses
import math
from dataclasses import dataclass, field
from typing import Callable, Mapping, Sequence

import numpy as np

from .errors import CablelabError

#: gravity of a dataset without a description, m/s^2
STANDARD_GRAVITY = 9.81

@dataclass(frozen=True)
class Param:
    """One model parameter.

    Args:
        name: short symbol, unique in a model (``M``, ``Fv``, ``Fc[winch_3]``).
        unit: SI unit text (``kg``, ``N s/m``).
        nominal: nominal / start value.
        lower, upper: physical box bounds (used by bounded least squares and outer searches).
        doc: one-line meaning.
    """

    name: str
    unit: str
    nominal: float = 0.0
    lower: float = -math.inf
    upper: float = math.inf
    doc: str = ""

    def renamed(self, name: str) -> "Param":
        return dataclasses.replace(self, name=name)


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

        return dataclasses.replace(
            self,
            t=self.t[idx], y=self.y[idx],
            signals={k: cut(v) for k, v in self.signals.items()},
            act_vel=cut(self.act_vel), act_map=cut(self.act_map), valid=self.valid[idx],
            regimes={k: cut(v) for k, v in self.regimes.items()},
            inputs={k: cut(v) for k, v in self.inputs.items()},
        )

    def replace(self, **changes) -> "Dataset":
        return dataclasses.replace(self, **changes)


RegressorFn = Callable[[Dataset], np.ndarray]
TransformFn = Callable[[Dataset, Mapping[str, float]], Dataset]


@dataclass(frozen=True)
class Effect:
    """One physical effect of the catalog (CONTRACT section 4).

    Args:
        id: stable catalog id (``joint_coulomb_friction``).
        plants: plants it applies to; ``("*",)`` = any plant.
        params: linear parameters (templates; per-actuator effects expand them per actuator).
        explanation: one-line physical explanation.
        signature: what its absence looks like in the residual (one line, used in diagnoses).
        reference: paper section behind it ("001 eq. 15").
        regressor: ``fn(ds) -> (N, C, p)`` column block for the linear parameters (p = number of
            expanded params); ``None`` if the effect has no linear parameter.
        per_actuator: expand each template param per actuator (``Fc[winch_1]``...) when the plant
            has more than one actuator.
        nonlinear: parameters searched outside the linear LS (bounded, separable LS).
        transform: ``fn(ds, values) -> ds`` applying the nonlinear parameters to the data
            (must set ``valid`` False where the result is undefined).
    """

    id: str
    plants: tuple[str, ...]
    params: tuple[Param, ...]
    explanation: str
    signature: str
    reference: str
    regressor: RegressorFn | None = None
    per_actuator: bool = False
    nonlinear: tuple[Param, ...] = ()
    transform: TransformFn | None = None

    def applies_to(self, plant: str) -> bool:
        return "*" in self.plants or plant in self.plants

    def columns(self, ds: Dataset) -> list[Param]:
        """The expanded linear parameters for this dataset (names unique per actuator, unit
        placeholders ``{effort}``, ``{position}``, ``{inertia}`` filled from ``ds.act_units``)."""
        def unit(p: Param, j: int) -> Param:
            if "{" not in p.unit:
                return p
            eu, pu = ds.act_units[j] if j < len(ds.act_units) else ("", "")
            inertia = "kg m^2" if pu == "rad" else "kg"
            return dataclasses.replace(p, unit=p.unit.format(effort=eu or "?", position=pu or "?",
                                                             inertia=inertia))

        acts = ds.actuators or ds.channels
        if not self.per_actuator or len(acts) <= 1:
            return [unit(p, 0) for p in self.params]
        return [unit(p, j).renamed(f"{p.name}[{a}]") for p in self.params for j, a in enumerate(acts)]

    def block(self, ds: Dataset) -> np.ndarray:
        """(N, C, p) regressor block, shape-checked."""
        cols = self.columns(ds)
        if self.regressor is None:
            return np.zeros((ds.n, ds.n_channels, 0))
        blk = np.asarray(self.regressor(ds), dtype=float)
        if blk.ndim == 2:
            blk = blk[:, None, :]
        if blk.shape != (ds.n, ds.n_channels, len(cols)):
            raise RuntimeError(f"effect {self.id}: regressor shape {blk.shape}, expected "
                               f"{(ds.n, ds.n_channels, len(cols))}")
        return blk


@dataclass(frozen=True)
class Model:
    """A plant, the effects it includes, and its known parameters.

    Args:
        plant: plant name.
        effects: effect ids, in order (the regressor columns follow this order).
        fixed: known parameter values by name, moved to the left-hand side of the fit.
    """

    plant: str
    effects: tuple[str, ...]
    fixed: Mapping[str, float] = field(default_factory=dict)

    def __post_init__(self) -> None:
        from .effects import get_effect

        seen = []
        for eid in self.effects:
            get_effect(eid, self.plant)  # validates id and applicability
            if eid in seen:
                raise CablelabError(f"effect {eid} listed twice in the model")
            seen.append(eid)
        object.__setattr__(self, "effects", tuple(self.effects))

    def with_effect(self, effect_id: str) -> "Model":
        return dataclasses.replace(self, effects=self.effects + (effect_id,))

    def effect_units(self) -> list[Effect]:
        from .effects import get_effect

        return [get_effect(e, self.plant) for e in self.effects]

    def nonlinear_params(self) -> list[Param]:
        return [p for e in self.effect_units() for p in e.nonlinear if p.name not in self.fixed]

    def apply_nonlinear(self, ds: Dataset, values: Mapping[str, float]) -> Dataset:
        """Apply every effect's data transform with the given nonlinear parameter values."""
        vals = {**{p.name: p.nominal for e in self.effect_units() for p in e.nonlinear},
                **{k: v for k, v in self.fixed.items()}, **dict(values)}
        for e in self.effect_units():
            if e.transform is not None:
                ds = e.transform(ds, vals)
        return ds

    def regressor(self, ds: Dataset) -> tuple[np.ndarray, list[Param], np.ndarray]:
        """Free regressor and the known part.

        Returns:
            ``(Phi, params, y_known)``: Phi (N, C, p) for the free linear parameters, their
            :class:`Param` list, and (N, C) the contribution of the fixed parameters.
        """
        blocks, cols = [], []
        for e in self.effect_units():
            blk = e.block(ds)
            blocks.append(blk)
            cols.extend(e.columns(ds))
        if blocks:
            phi = np.concatenate(blocks, axis=2)
        else:
            phi = np.zeros((ds.n, ds.n_channels, 0))
        names = [c.name for c in cols]
        for k in self.fixed:
            if k not in names and k not in {p.name for e in self.effect_units() for p in e.nonlinear}:
                raise CablelabError(f"fixed parameter {k!r} is not in the model (parameters: "
                                    f"{', '.join(names) or 'none'})")
        free = [i for i, nme in enumerate(names) if nme not in self.fixed]
        known = [i for i, nme in enumerate(names) if nme in self.fixed]
        y_known = np.zeros((ds.n, ds.n_channels))
        if known:
            vals = np.array([self.fixed[names[i]] for i in known])
            y_known = phi[:, :, known] @ vals
        return phi[:, :, free], [cols[i] for i in free], y_known

    def predict(self, ds: Dataset, params: Mapping[str, float]) -> tuple[np.ndarray, np.ndarray]:
        """Model output (N, C) and the valid mask for given parameter values (by name)."""
        ds2 = self.apply_nonlinear(ds, params)
        return self.linear_output(ds2, params), ds2.valid

    def linear_output(self, ds: Dataset, params: Mapping[str, float]) -> np.ndarray:
        """(N, C) linear part ``Phi theta + y_known`` on a dataset the nonlinear parameters are
        already applied to (:meth:`apply_nonlinear`)."""
        phi, cols, y_known = self.regressor(ds)
        theta = np.array([params[c.name] for c in cols]) if cols else np.zeros(0)
        return phi @ theta + y_known


def parse_effect_list(text: str | Sequence[str] | None) -> tuple[str, ...]:
    """``"a,b"`` -> ``("a", "b")`` (blank entries dropped)."""
    if text is None:
        return ()
    if isinstance(text, str):
        text = text.split(",")
    return tuple(s.strip() for s in text if s and s.strip())


def parse_fixed(items: Sequence[str] | None) -> dict:
    """``["M=95.1", "Fc=20"]`` -> ``{"M": 95.1, "Fc": 20.0}`` with one-line errors."""
    out = {}
    for item in items or ():
        for part in str(item).split(","):
            if not part.strip():
                continue
            if "=" not in part:
                raise CablelabError(f"--fix {part!r}: expected NAME=VALUE")
            k, v = part.split("=", 1)
            try:
                out[k.strip()] = float(v)
            except ValueError:
                raise CablelabError(f"--fix {part!r}: value {v!r} is not a number") from None
    return out
