"""The ``leg:`` section of the plant description (spec 003_leg.md sec. 5, CONTRACT section 3).

``parse_section(obj)`` validates the mapping and returns a :class:`LegDescription`; every problem is
a one-line :class:`~cablelab.errors.CablelabError` naming the key (``leg.link_length: missing
required key``). :meth:`LegDescription.params` gives the :class:`~.hybrid.LegParams` with the
nominal 003 Table 2 effect parameters.
"""
from __future__ import annotations

from dataclasses import dataclass

from ...fields import check_keys, fail, mapping, number
from .hybrid import LegParams

REQUIRED = ("spring_stiffness", "link_length")
OPTIONAL = ("mass", "free_angle", "spring_rest", "spring_preload", "encoder_resolution")


@dataclass(frozen=True)
class LegDescription:
    """Hopping leg of 003 (SI): k (N/m), L (m), theta_0 (rad), m (kg), z_0 (m), F_0 (N)."""

    spring_stiffness: float
    link_length: float
    mass: float = 1.55
    free_angle: float = 0.349066
    spring_rest: float | None = None
    spring_preload: float = 0.0
    encoder_resolution: float = 9.0e-5

    def params(self, gravity: float = 9.81, **effects) -> LegParams:
        """Model parameters: this description + Table 2 nominal d_s, d_f, betas (or ``effects``)."""
        return LegParams(m=self.mass, k=self.spring_stiffness, g=gravity, L=self.link_length,
                         theta0=self.free_angle, z0=self.spring_rest, F0=self.spring_preload, **effects)


def parse_section(obj) -> LegDescription:
    """Validate the ``leg:`` mapping (required: spring_stiffness, link_length)."""
    path = "leg"
    obj = mapping(obj, path)
    check_keys(obj, path, REQUIRED, OPTIONAL)
    L = number(obj, "link_length", path, positive=True)
    theta0 = number(obj, "free_angle", path, positive=True, default=0.349066)
    if theta0 >= 1.5707963:
        raise fail("leg.free_angle", f"expected an angle below pi/2 rad, got {theta0:g}")
    rest = number(obj, "spring_rest", path, positive=True)
    if rest is not None and rest >= 2 * L:
        raise fail("leg.spring_rest", f"expected a height below the fully extended leg 2 L = {2 * L:g} m, got {rest:g}")
    return LegDescription(
        spring_stiffness=number(obj, "spring_stiffness", path, positive=True),
        link_length=L,
        mass=number(obj, "mass", path, positive=True, default=1.55),
        free_angle=theta0,
        spring_rest=rest,
        spring_preload=number(obj, "spring_preload", path, nonneg=True, default=0.0),
        encoder_resolution=number(obj, "encoder_resolution", path, nonneg=True, default=9.0e-5),
    )


def leg_of(description) -> LegDescription:
    """The :class:`LegDescription` of a loaded description (one-line error without it)."""
    from ...errors import CablelabError

    leg = getattr(description, "leg", None)
    if leg is None:
        raise CablelabError("leg: missing required key (the section of the plant named by 'plant')")
    return leg


def load_leg_description(text: str = ""):
    """The loaded description of ``text`` (YAML file or text), or the package's data/leg.yaml when
    empty (the nodes' default)."""
    from pathlib import Path

    from ...description import load_description

    return load_description(text or Path(__file__).parent / "data" / "leg.yaml")
