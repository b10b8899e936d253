"""The CDPR's own options: which tension measurement and which pose the wrench uses. Each is also
a command-line option of the verbs that read a CDPR bag (``--tensions``, ``--pose``)."""
from __future__ import annotations

from dataclasses import dataclass

from ...plant_interface import option

TENSION_SOURCES = ("dynamometer", "motor", "both")
POSE_SOURCES = ("desired", "measured")


@dataclass(frozen=True)
class CdprOptions:
    """Attributes:
        tensions: ``dynamometer`` (the cable dynamometers), ``motor`` (R/r x motor torque) or
            ``both`` (dynamometer wrench + per-winch torque balance against the motor torques).
        pose: the pose of the wrench matrix W: ``desired`` (the reference, 001's real-time
            choice) or ``measured`` (``/cdpr/platform_pose``).
    """

    tensions: str = option(
        "dynamometer", choices=TENSION_SOURCES,
        help="cable tensions from the dynamometers (default), from the motor torques, or both "
             "(dynamometer wrench + per-winch torque balance against the motor torques)")
    pose: str = option("desired", choices=POSE_SOURCES, verbs=("estimate",),
                       help="pose for the wrench matrix (default desired, as 001)")
