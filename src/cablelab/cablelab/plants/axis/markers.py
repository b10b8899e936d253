"""The single axis in 3D (:mod:`cablelab.markers`), in the simulator's frame ``world``.

Prismatic: the carriage (a 0.1 m cube, the simulator's body) at x = q on a rail along world x.
Revolute: the pivot at the origin, the link turning about world y (q = 0 hanging down) to the
point mass at c = :func:`~.sim.pendulum_arm` (the simulator's load; 0.3 m drawn without a gravity
load) and the load there.
"""
from __future__ import annotations

import numpy as np

from ...markers import CUBE, SPHERE, Marker, decimate_times, line
from .sim import AxisTruth, pendulum_arm

#: rail half length (prismatic), link drawn without a gravity load (revolute), m
RAIL_HALF = 1.0
LINK = 0.3
JOINTS = "/axis/joint_states"


def link_length(desc, inertia: float | None = None) -> float:
    """Distance pivot -> load of the revolute axis: the simulator's c for ``inertia`` (default
    the description's), :data:`LINK` without a gravity load."""
    ax = desc.axis
    inertia = inertia or ax.inertia or AxisTruth.inertia
    c, _ = pendulum_arm(inertia, ax.gravity_moment or 0.0)
    return c if c > 0 else LINK


def axis_markers(desc, q: float, inertia: float | None = None) -> list[Marker]:
    """Markers of position ``q`` (m or rad); ``inertia``: the simulated axis's (sets the link
    length of a revolute axis with a gravity load)."""
    q = float(q)
    if desc.axis.joint_type == "prismatic":
        return [line("rail", 0, [[-RAIL_HALF, 0.0, -0.06], [RAIL_HALF, 0.0, -0.06]], (0.5, 0.5, 0.5, 1.0), 0.02),
                Marker(CUBE, "carriage", 0, (q, 0.0, 0.0), scale=(0.1, 0.1, 0.1), colour=(0.9, 0.6, 0.1, 1.0))]
    r = link_length(desc, inertia)
    tip = (-r * np.sin(q), 0.0, -r * np.cos(q))     # (0, 0, -r) turned by q about world y
    return [Marker(SPHERE, "pivot", 0, scale=(0.04, 0.04, 0.04), colour=(0.4, 0.4, 0.4, 1.0)),
            line("link", 0, [[0.0, 0.0, 0.0], tip], (0.9, 0.6, 0.1, 1.0), 0.02),
            Marker(SPHERE, "load", 0, tip, scale=(0.06, 0.06, 0.06), colour=(0.2, 0.4, 0.9, 1.0))]


def bag_markers(bag, desc):
    """``(t, frames)`` at about 30 Hz from the recorded joint position; None without it."""
    if desc is None or desc.axis is None or not (bag.has(JOINTS) and bag.counts.get(JOINTS)):
        return None
    s = bag.joint_state(JOINTS, ["joint"])
    q = s.position[:, 0]
    keep = decimate_times(s.t)
    keep = keep[np.isfinite(q[keep])]
    return s.t[keep], [axis_markers(desc, q[k]) for k in keep]
