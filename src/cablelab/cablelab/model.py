"""Models: a plant plus a set of effects plus known parameters.

:class:`Model` holds the :class:`~cablelab.effects.base.Effect` objects of its effects, looked up
once in the effect registry when the model is made. Linear in the free parameters:
``y = sum_e Phi_e @ theta_e``; fixed parameters are moved to the left-hand side.
"""
from __future__ import annotations

from dataclasses import dataclass, field
from typing import Mapping

import numpy as np

from .dataset import Dataset
from .effects import get_effect
from .effects.base import Effect, Param
from .errors import CablelabError


#: ``Dataset.signals`` key of a plant's parameter-free prediction (N, C) of the output channels,
#: part of every model's output (the known part, like fixed parameters)
KNOWN_OUTPUT = "known_output"


@dataclass(frozen=True)
class Model:
    """A plant, the effects it includes, and its known parameters.

    Args:
        plant: plant name.
        effects: effect ids or :class:`Effect` objects, in order (the regressor columns follow
            this order); stored as ids, with the looked-up objects in ``effect_objects``.
        fixed: known parameter values by name, moved to the left-hand side of the fit.
        unexcited: what a fit does with parameters the data cannot determine (a rank-deficient
            regressor): ``"raise"`` refuses with the unidentifiable directions named; ``"hold"``
            holds them at their description value (or the effect's neutral value) and says so
            (:func:`cablelab.fit.identify`, ``Identification.extra["held"]``).
        at: parameter values by name at which the effects' higher-order output terms
            (:attr:`~cablelab.effects.base.Effect.higher_order`) are evaluated when the values
            given to :meth:`evaluate` do not name them: the current estimate of an iterated fit
            (empty: the parameters' nominal values, where those terms vanish).
    """

    plant: str
    effects: tuple[str, ...]
    fixed: Mapping[str, float] = field(default_factory=dict)
    effect_objects: tuple[Effect, ...] = field(init=False, repr=False, compare=False)
    unexcited: str = "raise"
    at: Mapping[str, float] = field(default_factory=dict)

    def __post_init__(self) -> None:
        if self.unexcited not in ("raise", "hold"):
            raise ValueError(f"unexcited={self.unexcited!r}: expected 'raise' or 'hold'")
        objects: list[Effect] = []
        for e in self.effects:
            obj = e if isinstance(e, Effect) else get_effect(e, self.plant)  # validates id, plant
            if any(o.id == obj.id for o in objects):
                raise CablelabError(f"effect {obj.id} listed twice in the model")
            objects.append(obj)
        object.__setattr__(self, "effects", tuple(o.id for o in objects))
        object.__setattr__(self, "effect_objects", tuple(objects))

    def with_effect(self, effect: "str | Effect") -> "Model":
        """The model with one more effect (an id or an :class:`Effect`)."""
        return Model(self.plant, self.effect_objects + (effect,), self.fixed, unexcited=self.unexcited,
                     at=self.at)

    def with_effects(self, effects, fixed: Mapping[str, float] | None = None) -> "Model":
        """The same plant and policy with other effects (and known parameters)."""
        return Model(self.plant, tuple(effects), dict(self.fixed if fixed is None else fixed),
                     unexcited=self.unexcited, at=self.at)

    def evaluated_at(self, values: Mapping[str, float]) -> "Model":
        """The same model with its higher-order output terms evaluated at ``values``
        (:attr:`at`)."""
        return Model(self.plant, self.effect_objects, self.fixed, unexcited=self.unexcited,
                     at=dict(values))

    @property
    def higher_order(self) -> bool:
        """Whether an effect of the model has an output term beyond its columns."""
        return any(e.higher_order is not None for e in self.effect_objects)

    def nonlinear_params(self) -> list[Param]:
        return [p for e in self.effect_objects for p in e.nonlinear if p.name not in self.fixed]

    def apply_nonlinear(self, ds: Dataset, values: Mapping[str, float]) -> Dataset:
        """Apply every effect's data transform with the given nonlinear parameter values."""
        vals = {**{p.name: p.nominal for e in self.effect_objects for p in e.nonlinear},
                **{k: v for k, v in self.fixed.items()}, **dict(values)}
        for e in self.effect_objects:
            if e.transform is not None:
                ds = e.transform(ds, vals)
        return ds

    def regressor(self, ds: Dataset) -> tuple[np.ndarray, list[Param], np.ndarray]:
        """Free regressor and the known part (the effects' higher-order output terms at
        :attr:`at` and the fixed parameters: :meth:`evaluate` takes other values).

        Returns:
            ``(Phi, params, y_known)``: Phi (N, C, p) for the free linear parameters, their
            :class:`Param` list, and (N, C) the contribution of the fixed parameters and of the
            effects' higher-order terms; filtered by the dataset's parallel filter when it
            declares one (``ds.parallel_hz``).
        """
        return self._regressor(ds, None)

    def _regressor(self, ds: Dataset, values: Mapping[str, float] | None
                   ) -> tuple[np.ndarray, list[Param], np.ndarray]:
        blocks, cols = [], []
        for e in self.effect_objects:
            blk = e.block(ds)
            blocks.append(blk)
            cols.extend(e.columns(ds))
        if blocks:
            phi = np.concatenate(blocks, axis=2)
        else:
            phi = np.zeros((ds.n, ds.n_channels, 0))
        names = [c.name for c in cols]
        for k in self.fixed:
            if k not in names and k not in {p.name for e in self.effect_objects for p in e.nonlinear}:
                raise CablelabError(f"fixed parameter {k!r} is not in the model (parameters: "
                                    f"{', '.join(names) or 'none'})")
        free = [i for i, nme in enumerate(names) if nme not in self.fixed]
        known = [i for i, nme in enumerate(names) if nme in self.fixed]
        if ds.parallel_hz and phi.shape[2]:
            # parallel filtering (IDIM-LS): every column low-passed like the dataset's y
            from .parallel_filter import parallel_filter

            phi = parallel_filter(phi, ds.t, ds.parallel_hz)
        if known:
            phi_known, phi = phi[:, :, known], phi[:, :, free]
        # (every column free: phi, built above, is returned as it is, not copied again)
        nominal = ds.signals.get(KNOWN_OUTPUT)
        higher = self._higher_order(ds, values)
        if higher is not None:
            nominal = higher if nominal is None else \
                np.asarray(nominal, dtype=float).reshape(ds.n, ds.n_channels) + higher
        if nominal is not None:
            # the plant's own parameter-free prediction (e.g. MuJoCo's inverse dynamics of the
            # given model), filtered like the columns; a copy (the dataset's signal stays its own)
            nominal = np.asarray(nominal, dtype=float).reshape(ds.n, ds.n_channels)
            if ds.parallel_hz:
                from .parallel_filter import parallel_filter

                nominal = parallel_filter(nominal[:, :, None], ds.t, ds.parallel_hz)[:, :, 0]
            y_known = nominal + 0.0
        else:
            y_known = np.zeros((ds.n, ds.n_channels))
        if known:
            vals = np.array([self.fixed[names[i]] for i in known])
            y_known = y_known + phi_known @ vals
        return phi, [cols[i] for i in free], y_known

    def evaluate(self, ds: Dataset, values: Mapping[str, float]) -> "Evaluation":
        """The model on a dataset at given nonlinear parameter values (and linear ones, for the
        effects' higher-order output terms): the transformed dataset and its regressor, built
        once (what a fit solves and predicts with)."""
        ds2 = self.apply_nonlinear(ds, values)
        phi, cols, y_known = self._regressor(ds2, values) if self.higher_order else self.regressor(ds2)
        return Evaluation(ds2, phi, cols, y_known)

    def _higher_order(self, ds: Dataset, values: Mapping[str, float] | None) -> np.ndarray | None:
        """(N, C) sum of the effects' higher-order output terms at ``values`` over :attr:`at`
        and the fixed parameters (None when no effect has one)."""
        fns = [e.higher_order for e in self.effect_objects if e.higher_order is not None]
        if not fns:
            return None
        vals = {**self.at, **self.fixed, **dict(values or {})}
        return sum(np.asarray(fn(ds, vals), dtype=float).reshape(ds.n, ds.n_channels) for fn in fns)

    def predict(self, ds: Dataset, params: Mapping[str, float]) -> tuple[np.ndarray, np.ndarray]:
        """Model output (N, C) and the valid mask for given parameter values (by name)."""
        ev = self.evaluate(ds, params)
        return ev.output(params), ev.ds.valid


@dataclass(frozen=True)
class Evaluation:
    """A model evaluated on a dataset (:meth:`Model.evaluate`).

    Attributes:
        ds: the dataset after the effects' transforms (e.g. shifted by a delay).
        phi: (N, C, p) regressor of the free linear parameters (parallel-filtered when the
            dataset declares it).
        columns: their :class:`Param` list.
        y_known: (N, C) contribution of the fixed parameters.
    """

    ds: Dataset
    phi: np.ndarray
    columns: list
    y_known: np.ndarray

    @property
    def lhs(self) -> np.ndarray:
        """(N, C) what the free columns must explain: the measurement minus the known part."""
        return self.ds.y - self.y_known

    def output(self, params: "Mapping[str, float] | np.ndarray") -> np.ndarray:
        """(N, C) model output ``Phi theta + y_known``; ``params`` by name or the free
        parameters' values in column order."""
        if isinstance(params, Mapping):
            theta = np.array([params[c.name] for c in self.columns]) if self.columns else np.zeros(0)
        else:
            theta = np.asarray(params, dtype=float)
        return self.phi @ theta + self.y_known


__all__ = ["KNOWN_OUTPUT", "Evaluation", "Model"]
