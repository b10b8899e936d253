"""The ``axis:`` section of the plant description (CONTRACT section 3): a single drive."""
from __future__ import annotations

from dataclasses import dataclass
from typing import Any

from ...fields import check_keys, fail, mapping, number


@dataclass(frozen=True)
class AxisDescription:
    """Single drive: prismatic (m, kg, N) or revolute (rad, kg m^2, N m)."""

    joint_type: str
    inertia: float | None = None
    gravity_moment: float = 0.0  # m*c in kg m; load torque m*c*g*sin(q), q = 0 hanging down


def parse_section(obj: Any) -> AxisDescription:
    path = "axis"
    obj = mapping(obj, path)
    check_keys(obj, path, ("joint_type",), ("inertia", "gravity_moment"))
    jt = obj["joint_type"]
    if jt not in ("revolute", "prismatic"):
        raise fail("axis.joint_type", f"expected 'revolute' or 'prismatic', got {jt!r}")
    gm = number(obj, "gravity_moment", path, default=0.0)
    if jt == "prismatic" and gm:
        raise fail("axis.gravity_moment", "only applies to a revolute joint")
    return AxisDescription(joint_type=jt, inertia=number(obj, "inertia", path, positive=True),
                           gravity_moment=gm)
