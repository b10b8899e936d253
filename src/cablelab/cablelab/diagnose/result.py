"""The typed result of a diagnosis (``cablelab diagnose``, CONTRACT section 5).

:class:`Diagnosis` holds the baseline, the ranked :class:`Candidate` list and, in greedy mode, the
waterfall :class:`Step` list. ``to_json()`` is the contract JSON (``plant``, ``baseline``,
``ranking`` with ``effect``, ``error_before``, ``error_after``, ``params``, ``significant`` and the
documented extras); ``lines()`` the text the command prints. Built by
:mod:`cablelab.diagnose.ranking`; every consumer (command, report, fleet) reads this object.
"""
from __future__ import annotations

from dataclasses import dataclass, field
from typing import TYPE_CHECKING

if TYPE_CHECKING:
    from ..fit.identification import Identification
    from ..model import Model


#: keys of a ranking row that are part of the JSON, in order (contract keys first)
ROW_KEYS = ("effect", "error_before", "error_after", "params", "significant", "stderr", "units",
            "p_value", "delta_bic", "n_eff", "gain", "channels", "evidence", "identifiability",
            "ambiguous_with", "ambiguity", "held", "internal", "explanation")


@dataclass
class Candidate:
    """One ranked candidate effect (:func:`cablelab.diagnose.ranking.rank_candidates`).

    Attributes:
        effect: effect id.
        error_before, error_after: held-out error of the model without / with it (None after:
            it could not be fitted).
        params, stderr, units: its own fitted parameters in the user's terms, by name.
        significant: passes the held-out gain, the F-test and the identifiability check.
        explanation: one sentence (signature, values, gain, evidence, ambiguity).
        p_value, delta_bic, n_eff: the nested F-test and BIC against the model
            (:func:`~cablelab.diagnose.score.lr_significance`); gain: relative held-out drop on
            the channels it changes; channels: held-out NRMSE per channel with it.
        evidence: the regime where it lowers the residual most; identifiability: its
            confounding report (:mod:`.identifiability`).
        ambiguous_with, ambiguity: candidates the recording cannot tell it from (:mod:`.ambiguity`).
        held: its parameters the recording does not excite; internal: the regression's own
            coefficients its physical parameters replace.
    Fields left None are not in the JSON (:meth:`to_json`).
    """

    effect: str
    error_before: float | None
    error_after: float | None
    params: dict = field(default_factory=dict)
    significant: bool = False
    explanation: str | None = None
    stderr: dict | None = None
    units: dict | None = None
    p_value: float | None = None
    delta_bic: float | None = None
    n_eff: float | None = None
    gain: float | None = None
    channels: dict | None = None
    evidence: dict | None = None
    identifiability: dict | None = None
    ambiguous_with: list | None = None
    ambiguity: dict | None = None
    held: list | None = None
    internal: dict | None = None

    def to_json(self) -> dict:
        """The contract row: keys in :data:`ROW_KEYS` order, None fields left out (the held-out
        errors always present)."""
        return {k: getattr(self, k) for k in ROW_KEYS
                if getattr(self, k) is not None or k in ("error_after", "error_before")}


@dataclass(frozen=True)
class Step:
    """One step of the greedy waterfall: the model's effects, the one added (None first), its
    held-out error, identified parameters and the ranking of the remaining candidates;
    ``fit`` is that model's :class:`~cablelab.fit.Identification` on the whole record (not in
    the JSON: what the report and the overlay draw)."""

    effects: list
    added: str | None
    error: float
    params: dict
    stderr: dict
    units: dict
    ranking: list
    note: str | None = None
    fit: Identification | None = field(default=None, repr=False, compare=False)

    def to_json(self) -> dict:
        out = {"effects": self.effects, "added": self.added, "error": self.error,
               "params": self.params, "stderr": self.stderr, "units": self.units,
               "ranking": [c.to_json() for c in self.ranking]}
        if self.note:
            out["note"] = self.note
        return out


@dataclass(frozen=True)
class Diagnosis:
    """What a diagnosis found (see module docstring): the model's held-out error, the ranked
    :class:`Candidate` list and, in greedy mode, the waterfall :class:`Step` list.

    ``alpha`` and ``min_gain`` are the significance criteria it used; ``model`` and ``fit`` (the
    model and its :class:`~cablelab.fit.Identification` on the whole record) are what the report
    draws. None of these four is in the JSON."""

    plant: str
    baseline_effects: list
    baseline_error: float
    ranking: list
    folds: int
    greedy: list = field(default_factory=list)
    held: dict = field(default_factory=dict)
    held_warning: str | None = None
    alpha: float | None = None
    min_gain: float | None = None
    model: Model | None = field(default=None, repr=False, compare=False)
    fit: Identification | None = field(default=None, repr=False, compare=False)

    @property
    def final(self) -> Step | None:
        """The last waterfall step (greedy mode), else None."""
        return self.greedy[-1] if self.greedy else None

    def best_significant(self) -> Candidate | None:
        """The best-ranked significant candidate, or None."""
        return next((c for c in self.ranking if c.significant), None)

    def to_json(self) -> dict:
        out = {"plant": self.plant,
               "baseline": {"effects": self.baseline_effects, "error": self.baseline_error},
               "ranking": [c.to_json() for c in self.ranking], "folds": self.folds}
        if self.held:
            out["held"] = dict(self.held)
            out["warnings"] = [self.held_warning]
        if self.greedy:
            out["greedy"] = [s.to_json() for s in self.greedy]
            f = self.final
            out["final"] = {"effects": f.effects, "error": f.error, "params": f.params,
                            "stderr": f.stderr}
        return out

    def lines(self) -> list[str]:
        """The text report: baseline, ranking (``*`` = significant), waterfall, final values."""
        out = [f"plant {self.plant}: model {' + '.join(self.baseline_effects) or 'nominal (no effect added)'}, held-out NRMSE "
               f"{100 * self.baseline_error:.2f} % ({self.folds} folds)"]
        for i, c in enumerate(self.ranking, 1):
            after = "-" if c.error_after is None else f"{100 * c.error_after:.2f} %"
            mark = "*" if c.significant else " "
            out.append(f" {mark}{i}. {c.effect:<26} -> {after:>9}  {c.explanation or ''}")
        out.extend(ambiguity_lines(self.ranking))
        for s in self.greedy[1:]:
            out.append(f"  + {s.added:<26} held-out NRMSE {100 * s.error:.2f} %"
                       + (f"  ({s.note})" if s.note else ""))
        if self.final is not None:
            out.append("final: " + ", ".join(f"{k} = {v:.6g}" for k, v in self.final.params.items()))
        return out


def ambiguity_lines(ranking) -> list[str]:
    """One line per group of ambiguous :class:`Candidate` s: the data cannot tell them apart, so
    none of them is the answer."""
    out, seen = [], set()
    for c in ranking:
        others = c.ambiguous_with or []
        group = tuple(sorted({c.effect, *others}))
        if not others or group in seen:
            continue
        seen.add(group)
        out.append(f"ambiguous: {' and '.join([c.effect, *others])} explain the same residual "
                   "within noise; this recording cannot tell them apart, so the ranking names no "
                   "winner among them")
    return out


__all__ = ["Candidate", "Diagnosis", "Step", "ambiguity_lines"]
