"""Results that are physically impossible are never printed without a word: a mass or an inertia
that is negative or zero. A fit that explains the record with no mass (or anti-matter) means the
model or the measurement is wrong (signs, units, the geometry of the description), it is not a
result.

:func:`impossible_parameters` checks the identified parameters that a verb prints against their
effects' physical bounds (:class:`~cablelab.effects.base.Param` with a lower bound >= 0 and a
mass or inertia unit) and returns warning lines; ``compare``, ``identify`` and ``diagnose`` add
them to their ``"warnings"``, ``estimate`` checks its mean mass with :func:`impossible_mass`.
"""
from __future__ import annotations

import math

#: units of the parameters that must be > 0 (masses, inertias)
MASS_UNITS = ("kg", "kg m^2", "{inertia}")


def positive_parameters(effect_ids) -> set[str]:
    """Names of the mass / inertia parameters of these effects whose physical lower bound is 0."""
    from .effects import get_effect

    out = set()
    for e in effect_ids:
        try:
            eff = get_effect(e)
        except Exception:       # an unknown id was refused before; nothing to check
            continue
        out.update(p.name for p in tuple(eff.params) + tuple(eff.nonlinear)
                   if p.unit in MASS_UNITS and p.lower >= 0)
    return out


def impossible_parameters(values: dict, positive, units: dict | None = None,
                          where: str = "") -> list[str]:
    """Warning lines for the parameters in ``positive`` whose value is not > 0.

    Args:
        values: name -> value, or name -> ``{"value", "unit", "fixed"}`` (a verb's ``"params"``;
            fixed parameters are the user's and not checked).
        positive: names that must be > 0 (:func:`positive_parameters`).
        units: name -> unit when ``values`` holds plain numbers.
        where: prefix of the line (e.g. ``"diagnose: candidate platform_inertia"``).
    """
    out = []
    for name, v in (values or {}).items():
        if name not in positive:
            continue
        if isinstance(v, dict):
            if v.get("fixed"):
                continue
            value, unit = v.get("value"), v.get("unit", "")
        else:
            value, unit = v, (units or {}).get(name, "")
        if not isinstance(value, (int, float)):
            continue
        if not (math.isfinite(value) and value > 0):
            out.append(impossible_line(name, float(value), unit or "", where))
    return out


def impossible_line(name: str, value: float, unit: str, where: str = "") -> str:
    """``PHYSICALLY IMPOSSIBLE: m = -904 kg (a negative mass); ...``."""
    what = "negative" if value < 0 else ("zero" if value == 0 else "undefined")
    kind = "mass" if unit == "kg" else "inertia"
    pre = f"{where}: " if where else ""
    return (f"{pre}PHYSICALLY IMPOSSIBLE: {name} = {value:.4g} {unit} (a {what} {kind}); the model "
            f"or the measurement is wrong (signs, units, the geometry in the description): do not "
            f"use this result")


def impossible_mass(mass_mean, where: str = "estimate") -> list[str]:
    """Warning line for a mean mass estimate that is not > 0."""
    if isinstance(mass_mean, (int, float)) and math.isfinite(mass_mean) and mass_mean > 0:
        return []
    return [impossible_line("mass", float(mass_mean), "kg", where)]
