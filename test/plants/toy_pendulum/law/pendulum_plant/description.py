"""The ``pendulum:`` section of a plant description: parsed and validated with cablelab's public
field validators (one-line errors naming the key path), dumped back as a mapping."""
from __future__ import annotations

import dataclasses
from dataclasses import dataclass

from cablelab.fields import check_keys, mapping, number


@dataclass(frozen=True)
class PendulumDescription:
    """``pendulum:`` section: bob mass (kg), rod length (m); a point-like bob on a massless rod."""

    mass: float
    length: float

    @property
    def inertia(self) -> float:
        """Inertia about the hinge, kg m^2 (m l^2)."""
        return self.mass * self.length ** 2


def parse_section(obj) -> PendulumDescription:
    """The validated section (``obj``: the YAML mapping under ``pendulum:``)."""
    obj = mapping(obj, "pendulum")
    check_keys(obj, "pendulum", ("mass", "length"), ())
    return PendulumDescription(number(obj, "mass", "pendulum", positive=True),
                               number(obj, "length", "pendulum", positive=True))


def dump_section(section: PendulumDescription) -> dict:
    """The section as the mapping :func:`parse_section` reads."""
    return dataclasses.asdict(section)
