"""What an effect of the catalog is (CONTRACT section 4): :class:`Param` (one physical
parameter: name, SI unit, nominal value, box bounds) and :class:`Effect` (one physical phenomenon:
its parameters and its contribution as a regressor column block ``Phi_e(data)`` (N, C, p_e), model
linear in the parameters, and/or a data ``transform`` driven by a few nonlinear parameters, e.g. a
time delay, searched outside the linear least squares). The pattern is 002 eq. 4.2
(``tau = Y(q, qd, qdd) pi``) generalised to any set of effects.
"""
from __future__ import annotations

import dataclasses
import math
from dataclasses import dataclass
from typing import Callable, Mapping

import numpy as np

from ..dataset import Dataset


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


@dataclass(frozen=True)
class Physical:
    """A parameter as the description, the spec or the paper names it, computed from the fitted
    ones (e.g. beta_td = 1 - c_td / m of 003 eq. 24 from the impact effect's momentum column).

    Args:
        name: the paper's / spec's symbol (``beta_td``, ``d_ry``); unit: SI unit text.
        value: ``fn(params) -> float`` from every model parameter by name (fitted and fixed).
        doc: one-line meaning, with where the name comes from.
    """

    name: str
    unit: str
    value: Callable[[Mapping[str, float]], float]
    doc: str = ""


RegressorFn = Callable[[Dataset], np.ndarray]
TransformFn = Callable[[Dataset, Mapping[str, float]], Dataset]
HigherOrderFn = Callable[[Dataset, Mapping[str, float]], np.ndarray]


@dataclass(frozen=True)
class Effect:
    """One physical effect of the catalog (CONTRACT section 4).

    Args:
        id: stable catalog id (``joint_coulomb_friction``).
        plants: plants it applies to; ``("*",)`` = any plant that has the capability in
            ``requires``.
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
        derived: optional ``fn(effect, own, all_params, ds) -> {name: value}``: values reported
            beside the fitted parameters (e.g. the contract's F_s, v_s of a Stribeck effect).
        described: optional ``fn(ds) -> {param name: value}``: the values the plant description
            gives the effect's parameters (e.g. the levelling gains of a suspended platform's
            parameter set); a parameter the data do not excite is held there (else at its
            ``Param.nominal``, the effect's neutral value).
        physical: optional ``fn(ds) -> [Physical, ...]``: the parameters reported to the user
            when the fitted ones are internal regression coefficients (a momentum in kg for a
            velocity ratio, a torque for a pose offset); ``None``: the effect's own parameters
            are the physical ones.
        requires: a capability the plant must declare (:attr:`cablelab.registry.Plant.
            capabilities`, e.g. ``"joint_actuators"``); ``None`` = no requirement.
        higher_order: optional ``fn(ds, values) -> (N, C)``: the part of the effect's output
            that is not linear in its own linear parameters, at the parameter values given by
            name (those missing: their ``Param.nominal``), small next to the columns' part
            (e.g. the second-order shortening of the vertical gravity by a base tilt whose
            columns are first order in the angles). The model adds it to its known part at
            the current estimate and :func:`cablelab.fit.identify` refits until the estimate
            settles, so the columns stay linear and the output is exact.
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
    requires: str | None = None
    derived: Callable | None = None
    described: Callable | None = None
    physical: Callable | None = None
    higher_order: HigherOrderFn | None = None

    def applies_to(self, plant: str, capabilities=frozenset()) -> bool:
        """Whether the effect applies to ``plant`` with these capabilities."""
        named = "*" in self.plants or plant in self.plants
        return named and (self.requires is None or self.requires in capabilities)

    def applies_doc(self) -> str:
        """Where the effect applies, in words (for messages)."""
        who = "any plant" if "*" in self.plants else ", ".join(self.plants)
        return f"{who} with {self.requires}" if self.requires else who

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
