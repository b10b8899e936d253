"""The typed result of a diagnosis (``cablelab diagnose``, CONTRACT section 5).

:class:`Diagnosis` holds the baseline, the ranked :class:`Candidate` list and, in greedy mode, the
waterfall :class:`Step` list. ``to_json()`` is the contract JSON (``plant``, ``baseline``,
``ranking`` with ``effect``, ``error_before``, ``error_after``, ``params``, ``significant`` and the
documented extras); ``lines()`` the text the command prints. Built once from the ranking rows of
:mod:`cablelab.diagnose.ranking`; every consumer (command, report, fleet) reads this object.
"""
from __future__ import annotations

from dataclasses import dataclass, field

#: keys of a ranking row that are part of the JSON, in order (contract keys first)
ROW_KEYS = ("effect", "error_before", "error_after", "params", "significant", "stderr", "units",
            "p_value", "delta_bic", "n_eff", "gain", "channels", "evidence", "identifiability",
            "ambiguous_with", "ambiguity", "held", "internal", "explanation")


@dataclass(frozen=True)
class Candidate:
    """One ranked candidate effect: held-out errors before/after, its own fitted parameters
    (name -> value, with ``stderr`` and ``units``), significance and the one-line explanation;
    ``extra`` holds any further documented fields the ranking reports (JSON order kept)."""

    effect: str
    error_before: float | None
    error_after: float | None
    params: dict
    significant: bool
    explanation: str | None = None
    extra: dict = field(default_factory=dict)

    @classmethod
    def from_row(cls, row: dict) -> "Candidate":
        """From a ranking row (:func:`cablelab.diagnose.ranking.rank_candidates`)."""
        return cls(effect=row["effect"], error_before=row.get("error_before"),
                   error_after=row.get("error_after"), params=row.get("params") or {},
                   significant=bool(row.get("significant")), explanation=row.get("explanation"),
                   extra={k: row[k] for k in ROW_KEYS[5:-1] if k in row})

    def to_json(self) -> dict:
        base = {"effect": self.effect, "error_before": self.error_before,
                "error_after": self.error_after, "params": self.params,
                "significant": self.significant, **self.extra, "explanation": self.explanation}
        return {k: base[k] for k in ROW_KEYS if k in base and base[k] is not None
                or k in ("error_after", "error_before")}


@dataclass(frozen=True)
class Step:
    """One step of the greedy waterfall: the model's effects, the one added (None first), its
    held-out error, identified parameters and the ranking of the remaining candidates."""

    effects: list
    added: str | None
    error: float
    params: dict
    stderr: dict
    units: dict
    ranking: list
    note: str | None = None

    def to_json(self) -> dict:
        out = {"effects": self.effects, "added": self.added, "error": self.error,
               "params": self.params, "stderr": self.stderr, "units": self.units,
               "ranking": [c.to_json() for c in self.ranking]}
        if self.note:
            out["note"] = self.note
        return out


@dataclass(frozen=True)
class Diagnosis:
    """What ``cablelab diagnose`` found (see module docstring)."""

    plant: str
    baseline_effects: list
    baseline_error: float
    ranking: list
    folds: int
    greedy: list = field(default_factory=list)
    held: dict = field(default_factory=dict)
    held_warning: str | None = None

    @property
    def final(self) -> Step | None:
        """The last waterfall step (greedy mode), else None."""
        return self.greedy[-1] if self.greedy else None

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
    """One line per group of ambiguous candidates (ranking rows or :class:`Candidate`): the data
    cannot tell them apart, so none of them is the answer."""
    out, seen = [], set()
    for c in ranking:
        row = c.to_json() if isinstance(c, Candidate) else c
        others = row.get("ambiguous_with") or []
        group = tuple(sorted({row["effect"], *others}))
        if not others or group in seen:
            continue
        seen.add(group)
        out.append(f"ambiguous: {' and '.join([row['effect'], *others])} explain the same residual "
                   "within noise; this recording cannot tell them apart, so the ranking names no "
                   "winner among them")
    return out


def excite_commands(ranking, plant: str, source: str, held=()) -> list[str]:
    """For every confounded pair of a ranking (``identifiability.confounded``) and the parameters
    the recording left unexcited (``held``, and candidates' ``held``), the exact
    ``cablelab excite`` command that designs the experiment separating them (one line each);
    a plant without experiment design gets one line saying so."""
    import shlex

    groups: list[tuple[str, ...]] = []
    for c in ranking:
        row = c.to_json() if isinstance(c, Candidate) else c
        for r in (row.get("identifiability") or {}).get("confounded", []):
            pair = tuple(sorted((r["param"], r["with"])))
            if pair not in groups:
                groups.append(pair)
        if row.get("held"):
            g = tuple(row["held"])
            if g not in groups:
                groups.append(g)
    if held and tuple(held) not in groups:
        groups.append(tuple(held))
    if not groups:
        return []
    from ..errors import CablelabError
    from ..excite import get_exciter

    try:
        get_exciter(plant)
    except CablelabError as exc:
        return [f"to separate {', '.join(' and '.join(g) for g in groups)}: {exc}"]
    bag = shlex.quote(str(source)) if source else "BAG"
    return [f"to separate {' and '.join(g)}: cablelab excite {bag} --params "
            f"{shlex.quote(','.join(g))} --duration 60 -o excite_{'_'.join(_slug(x) for x in g)}"
            for g in groups]


def _slug(name: str) -> str:
    return "".join(ch if ch.isalnum() else "_" for ch in name).strip("_")


def step_from_dict(s: dict) -> Step:
    return Step(effects=list(s["effects"]), added=s["added"], error=s["error"], params=s["params"],
                stderr=s["stderr"], units=s["units"],
                ranking=[Candidate.from_row(r) for r in s["ranking"]], note=s.get("note"))


__all__ = ["Candidate", "Diagnosis", "Step", "ambiguity_lines", "excite_commands", "step_from_dict"]
