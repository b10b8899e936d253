"""The hopping leg in 3D (:mod:`cablelab.markers`), frame ``world`` (z up, ground at z = 0).

The body (hip) at height z on the vertical guide; the two links of length L (003 eq. 2) from the
hip to the knee and from the knee to the foot, which stands on the ground in stance and hangs at
the frozen leg length ``l_fl`` below the body in flight (spec E1); the parallel spring from hip
to foot coloured by its force (:func:`~.hybrid.spring_force` at the leg length; blue 0 to red at
three times the leg's weight); the ground.
"""
from __future__ import annotations

import numpy as np

from ...markers import CUBE, SPHERE, Marker, decimate_times, line, tension_colour
from .hybrid import STANCE, LegParams, spring_force

JOINTS, CONTACT = "/leg/joint_states", "/leg/contact"


def leg_markers(p: LegParams, z: float, foot: float = 0.0) -> list[Marker]:
    """Markers of body height ``z`` and foot height ``foot`` (m)."""
    z, foot = float(z), float(foot)
    half = 0.5 * (z - foot)
    knee = (float(np.sqrt(max(p.L * p.L - half * half, 0.0))), 0.0, z - half)
    force = max(float(spring_force(z - foot, p)), 0.0)
    colour = tension_colour(force, 3.0 * p.flight_mass * p.g)
    return [line("ground", 0, [[-0.3, 0.0, 0.0], [0.3, 0.0, 0.0]], (0.5, 0.5, 0.5, 1.0), 0.01),
            Marker(CUBE, "body", 0, (0.0, 0.0, z), scale=(0.12, 0.08, 0.04), colour=(0.3, 0.3, 0.35, 0.9)),
            line("links", 0, [[0.0, 0.0, z], knee, [0.0, 0.0, foot]], (0.9, 0.6, 0.1, 1.0), 0.015),
            line("spring", 0, [[0.0, 0.0, z], [0.0, 0.0, foot]], colour, 0.01),
            Marker(SPHERE, "foot", 0, (0.0, 0.0, foot), scale=(0.03, 0.03, 0.03), colour=(0.2, 0.2, 0.2, 1.0))]


def sim_markers(sim) -> list[Marker]:
    """Markers of a :class:`~.sim.LegSim`'s current state."""
    return leg_markers(sim.p, sim.z, 0.0 if sim.phase == STANCE else sim.z - sim.l_fl)


def foot_heights(z, contact, z_td: float) -> np.ndarray:
    """Foot height (m) along a record: 0 in stance; in flight the body height minus the leg length
    frozen at lift-off, ``min(z_td, z)`` at the last stance sample (``z_td`` before any stance)."""
    z = np.asarray(z, float)
    stance = np.asarray(contact, float) > 0.5
    last = np.maximum.accumulate(np.where(stance, np.arange(len(z)), -1))
    l_fl = np.where(last >= 0, np.minimum(z_td, z[np.maximum(last, 0)]), z_td)
    return np.where(stance, 0.0, z - l_fl)


def bag_markers(bag, desc):
    """``(t, frames)`` at about 30 Hz from the recorded body height and contact switch; None
    without them."""
    if desc is None or getattr(desc, "leg", None) is None or \
            not all(bag.has(tp) and bag.counts.get(tp) for tp in (JOINTS, CONTACT)):
        return None
    p = desc.leg.params(desc.gravity)
    js = bag.joint_state(JOINTS, ["body"])
    c = bag.joint_state(CONTACT, ["contact"])
    z = js.position[:, 0]
    ok = np.isfinite(z)
    t, z = js.t[ok], z[ok]
    contact = np.interp(t, c.t, np.nan_to_num(c.position[:, 0]))
    foot = foot_heights(z, contact, p.z_td)
    keep = decimate_times(t)
    return t[keep], [leg_markers(p, z[k], foot[k]) for k in keep]
