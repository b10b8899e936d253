"""The ``crane:`` section of the plant description (CONTRACT section 3): boom length, masses and
the optional counterbalance of the boom crane of 002."""
from __future__ import annotations

from dataclasses import dataclass
from typing import Any

from ...fields import check_keys, mapping, number


@dataclass(frozen=True)
class Counterbalance:
    mass: float
    distance: float


@dataclass(frozen=True)
class CraneDescription:
    """Boom crane of 002: boom length l_b (m), masses (kg), optional counterbalance."""

    boom_length: float
    payload_mass: float | None = None
    boom_mass: float | None = None
    counterbalance: Counterbalance | None = None


def parse_section(obj: Any) -> CraneDescription:
    path = "crane"
    obj = mapping(obj, path)
    check_keys(obj, path, ("boom_length",), ("payload_mass", "boom_mass", "counterbalance"))
    cb = None
    if obj.get("counterbalance") is not None:
        cbo = mapping(obj["counterbalance"], "crane.counterbalance")
        check_keys(cbo, "crane.counterbalance", ("mass", "distance"), ())
        cb = Counterbalance(number(cbo, "mass", "crane.counterbalance", nonneg=True),
                            number(cbo, "distance", "crane.counterbalance", nonneg=True))
    return CraneDescription(
        boom_length=number(obj, "boom_length", path, positive=True),
        payload_mass=number(obj, "payload_mass", path, positive=True),
        boom_mass=number(obj, "boom_mass", path, nonneg=True),
        counterbalance=cb,
    )
