"""The ``suspended:`` section of a plant description (spec 000_suspended.md sec. 5.1).

:func:`parse_section` validates the mapping with the shared helpers of
:mod:`cablelab.description` and returns a :class:`SuspendedDescription`; every error is one line
naming the key (``suspended.cable_length: expected a positive number, got -1``).
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from ...fields import check_keys, fail, mapping, number, vector
from .params import VARIANTS, VirtualParams, parameter_set

__all__ = ["SuspendedDescription", "parse_section", "KEYS"]

KEYS = ("variant", "cable_length", "suspension_point", "cable_separation", "platform_mass",
        "platform_com", "arm_mount", "payload_mass", "parameter_set", "platform_inertia")


@dataclass(frozen=True)
class SuspendedDescription:
    """Validated ``suspended:`` section (SI units).

    Args:
        variant: ``licas`` | ``cranebot``. cable_length: L, m. suspension_point: S (3,), m.
        cable_separation: m or None (single rope/hook). platform_mass: kg or None.
        platform_com: (3,) m. arm_mount: (2, 3) m. payload_mass: kg.
        parameter_set: ``repo`` | ``table5`` (nominal virtual-joint parameters).
        platform_inertia: (3,) principal inertia of the platform, kg m^2, or None.
    """

    variant: str
    cable_length: float
    suspension_point: np.ndarray
    cable_separation: float | None
    platform_mass: float | None
    platform_com: np.ndarray
    arm_mount: np.ndarray
    payload_mass: float
    parameter_set: str = "repo"
    platform_inertia: np.ndarray | None = None

    def params(self) -> VirtualParams:
        """The nominal virtual-joint parameter set with the description's geometry applied."""
        p = parameter_set(self.variant, self.parameter_set)
        return p.replace(L=float(self.cable_length), S=tuple(map(float, self.suspension_point)),
                         arm_mount=tuple(map(float, self.arm_mount[0])))


def parse_section(obj, path: str = "suspended") -> SuspendedDescription:
    """Validate the ``suspended:`` mapping.

    Raises:
        CablelabError: unknown key or variant, negative length/mass, inconsistent inertia (one
            line naming the key).
    """
    obj = mapping(obj, path)
    check_keys(obj, path, ("variant",), KEYS[1:])
    variant = obj["variant"]
    if variant not in VARIANTS:
        raise fail(f"{path}.variant", f"unknown variant {variant!r} (expected one of {', '.join(VARIANTS)})")
    pset = obj.get("parameter_set", "repo")
    if pset not in ("repo", "table5"):
        raise fail(f"{path}.parameter_set", f"unknown parameter set {pset!r} (expected repo or table5)")
    nominal = parameter_set(variant, "repo")
    L = number(obj, "cable_length", path, positive=True, default=nominal.L)
    S = vector(obj, "suspension_point", path, default=nominal.S)
    sep = number(obj, "cable_separation", path, positive=True)
    mp = number(obj, "platform_mass", path, positive=True)
    com = vector(obj, "platform_com", path, default=nominal.c_plat)
    payload = number(obj, "payload_mass", path, nonneg=True, default=0.0)
    mount_default = [nominal.arm_mount, tuple(np.array(nominal.arm_mount) * [1, -1, 1])]
    mounts = obj.get("arm_mount", mount_default)
    if not isinstance(mounts, (list, tuple)) or len(mounts) != 2:
        raise fail(f"{path}.arm_mount", f"expected two 3-vectors (left, right), got {mounts!r}")
    arm_mount = np.stack([vector({"m": m}, "m", f"{path}.arm_mount[{i}]") for i, m in enumerate(mounts)])
    inertia = None
    if "platform_inertia" in obj:
        inertia = vector(obj, "platform_inertia", path)
        a, b, c = inertia
        if min(inertia) <= 0 or a + b < c or a + c < b or b + c < a:
            raise fail(f"{path}.platform_inertia", f"inconsistent principal inertia {list(map(float, inertia))} "
                        "kg m^2 (each must be > 0 and A + B >= C, spec D8)")
    return SuspendedDescription(variant, float(L), S, sep, mp, com, arm_mount, float(payload), pset, inertia)
