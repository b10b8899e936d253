"""The ``pendulum:`` section of a plant description: parsed and validated with cablelab's public
field validators (one-line errors naming the key path), dumped back as a mapping."""
from __future__ import annotations

import dataclasses
from dataclasses import dataclass

from cablelab.fields import check_keys, mapping, number


@dataclass(frozen=True)
class PendulumDescription:
    """``pendulum:`` section. inertia: of the moving body about the hinge, kg m^2."""

    inertia: float


def parse_section(obj) -> PendulumDescription:
    """The validated section (``obj``: the YAML mapping under ``pendulum:``)."""
    obj = mapping(obj, "pendulum")
    check_keys(obj, "pendulum", ("inertia",), ())
    return PendulumDescription(number(obj, "inertia", "pendulum", positive=True))


def dump_section(section: PendulumDescription) -> dict:
    """The section as the mapping :func:`parse_section` reads."""
    return dataclasses.asdict(section)
