"""The typed results of ``cablelab compare`` and ``cablelab identify`` (CONTRACT section 5).

:class:`Comparison` (:func:`cablelab.workbench.compare`) and :class:`IdentifyReport`
(:func:`cablelab.workbench.identify_report`) hold what the verbs report; ``to_json()`` is the
verb's JSON, key for key. The diagnosis has its own, :class:`cablelab.diagnose.result.Diagnosis`.
Each keeps the :class:`~cablelab.fit.Identification` it reports on as ``fit`` (not in the JSON).
"""
from __future__ import annotations

from dataclasses import asdict, dataclass, field
from typing import TYPE_CHECKING

if TYPE_CHECKING:
    from .fit.identification import Identification



def _with_held(out: dict, held: dict, held_warning: str | None) -> dict:
    """``out`` with ``"held"`` (name -> value) and its line in ``"warnings"`` when the fit held
    parameters the recording does not excite."""
    if held:
        out["held"] = dict(held)
        out.setdefault("warnings", []).append(held_warning)
    return out


@dataclass(frozen=True)
class Comparison:
    """Measured vs model on one recording (the model fitted on the whole record).

    Attributes:
        plant, effects, samples: the plant, the model's effects, the valid samples fitted.
        channels: channel -> :func:`~cablelab.diagnose.metrics.channel_metrics` dict.
        worst_segments: :func:`~cablelab.diagnose.localise.worst_segments` rows.
        params: parameter -> ``{"value", "stderr", "unit", "fixed"}`` (``"held": True`` for one
            the recording does not excite).
        regimes: :func:`~cablelab.diagnose.localise.residual_by_regime` rows.
        whiteness: channel -> summary of the residual's whiteness test.
        rank, condition: of the regressor.
        held, held_warning: parameters held at their description values, and the warning.
        free_run: the plant's free-run comparison (None: the plant has none).
        fit: the :class:`~cablelab.fit.Identification` (not in the JSON).
    """

    plant: str
    effects: list
    samples: int
    channels: dict
    worst_segments: list
    params: dict
    regimes: list
    whiteness: dict
    rank: int
    condition: float
    held: dict = field(default_factory=dict)
    held_warning: str | None = None
    free_run: dict | None = None
    fit: Identification | None = field(default=None, repr=False, compare=False)

    def to_json(self) -> dict:
        out: dict = {"plant": self.plant, "effects": list(self.effects), "samples": self.samples,
                     "channels": dict(self.channels)}
        for ch, m in self.channels.items():      # each channel's metrics also at the top level
            out.setdefault(ch, m)
        out.update({"worst_segments": self.worst_segments, "params": self.params,
                    "regimes": self.regimes, "whiteness": self.whiteness, "rank": self.rank,
                    "condition": self.condition})
        _with_held(out, self.held, self.held_warning)
        if self.free_run is not None:
            out["free_run"] = self.free_run
        return out


@dataclass(frozen=True)
class FitQuality:
    """How well an identified model fits (the ``"fit"`` object of ``cablelab identify``).

    Attributes:
        nrmse: in-sample NRMSE, mean over the channels that have one; cv_nrmse: held-out
            (blocked k-fold, ``folds``; None when ``folds`` is 0).
        channels: channel -> :func:`~cablelab.diagnose.metrics.channel_metrics` dict.
        rank, parameters, condition: of the regressor; unidentifiable: its unidentifiable
            directions; active_bounds: parameters at a bound.
    """

    nrmse: float | None
    cv_nrmse: float | None
    folds: int
    channels: dict
    rank: int
    parameters: int
    condition: float
    unidentifiable: list
    active_bounds: list


@dataclass(frozen=True)
class IdentifyReport:
    """A model's identified parameters with standard errors and its fit quality.

    Attributes:
        plant, effects, samples: the plant, the model's effects, the valid samples fitted.
        params: parameter -> ``{"value", "stderr", "unit", "fixed"}`` in the user's terms (the
            effects' physical parameters where they have them).
        quality: :class:`FitQuality` (``"fit"`` in the JSON).
        held, held_warning: parameters held at their description values, and the warning.
        internal: the regression's own coefficients the physical parameters replace (empty: none).
        simulation: the simulation-based refinement (None: not asked for).
        fit: the :class:`~cablelab.fit.Identification` (not in the JSON).
    """

    plant: str
    effects: list
    samples: int
    params: dict
    quality: FitQuality
    held: dict = field(default_factory=dict)
    held_warning: str | None = None
    internal: dict = field(default_factory=dict)
    simulation: dict | None = None
    fit: Identification | None = field(default=None, repr=False, compare=False)

    def to_json(self) -> dict:
        out = {"plant": self.plant, "effects": list(self.effects), "samples": self.samples,
               "params": self.params, "fit": asdict(self.quality)}
        _with_held(out, self.held, self.held_warning)
        if self.internal:
            out["internal"] = self.internal
        if self.simulation is not None:
            out["simulation"] = self.simulation
        return out


__all__ = ["Comparison", "FitQuality", "IdentifyReport"]
