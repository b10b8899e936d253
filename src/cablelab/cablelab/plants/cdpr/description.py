"""The ``cdpr:`` section of the plant description (CONTRACT section 3): exit points, anchor
points, swivel axes, drums and pulleys of a CDPR (001 sec. II)."""
from __future__ import annotations

from dataclasses import dataclass, field
from typing import Any

import numpy as np

from ...fields import check_keys, fail, mapping, number, vector


@dataclass(frozen=True)
class Cable:
    """One cable: exit point A_i (world), anchor point B_i (platform frame), pulley swivel axis."""

    exit_point: np.ndarray
    anchor_point: np.ndarray
    swivel_axis: np.ndarray = field(default_factory=lambda: np.array([0.0, 0.0, 1.0]))


@dataclass(frozen=True)
class CdprDescription:
    """CDPR geometry and drives (001 sec. II). Lengths in m, masses in kg."""

    drum_radius: float
    gear_ratio: float
    cables: tuple[Cable, ...]
    platform_mass: float | None = None
    pulley_radius: float = 0.0  # 0 = pulleys unknown / treated as points (Model I)

    @property
    def exit_points(self) -> np.ndarray:
        """(n, 3) exit points A_i in world."""
        return np.array([c.exit_point for c in self.cables])

    @property
    def anchor_points(self) -> np.ndarray:
        """(n, 3) anchor points B_i in the platform frame."""
        return np.array([c.anchor_point for c in self.cables])

    @property
    def swivel_axes(self) -> np.ndarray:
        """(n, 3) unit swivel axes."""
        return np.array([c.swivel_axis for c in self.cables])


def parse_section(obj: Any) -> CdprDescription:
    path = "cdpr"
    obj = mapping(obj, path)
    check_keys(obj, path, ("drum_radius", "gear_ratio", "cables"), ("platform_mass", "pulley_radius"))
    cables_raw = obj["cables"]
    if not isinstance(cables_raw, list) or not cables_raw:
        raise fail("cdpr.cables", "expected a non-empty list of cables")
    cables = []
    for i, c in enumerate(cables_raw):
        cp = f"cdpr.cables[{i}]"
        c = mapping(c, cp)
        check_keys(c, cp, ("exit_point", "anchor_point"), ("swivel_axis",))
        axis = vector(c, "swivel_axis", cp, default=[0.0, 0.0, 1.0])
        norm = float(np.linalg.norm(axis))
        if norm < 1e-9:
            raise fail(f"{cp}.swivel_axis", "must not be the zero vector")
        cables.append(Cable(vector(c, "exit_point", cp), vector(c, "anchor_point", cp), axis / norm))
    return CdprDescription(
        drum_radius=number(obj, "drum_radius", path, positive=True),
        gear_ratio=number(obj, "gear_ratio", path, positive=True),
        cables=tuple(cables),
        platform_mass=number(obj, "platform_mass", path, positive=True),
        pulley_radius=number(obj, "pulley_radius", path, nonneg=True, default=0.0),
    )


def dump_section(sec: CdprDescription) -> dict:
    """The section as a plain mapping (cables as a list of mappings)."""
    from ...description import plain

    d = {k: v for k, v in plain(sec).items() if v is not None}
    d["cables"] = [{k: plain(v) for k, v in vars(c).items()} for c in sec.cables]
    return d
