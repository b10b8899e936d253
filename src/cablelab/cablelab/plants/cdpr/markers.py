"""The CDPR in 3D (:mod:`cablelab.markers`): eight cables from the exit points A_i to the anchor
points p + R B_i coloured by tension, the platform (a box spanning the anchor points), the exit
points and the frame's outline."""
from __future__ import annotations

import numpy as np

from ...markers import CUBE, LINE_LIST, SPHERE_LIST, Marker, decimate_times, line, tension_colour
from ...rotations import matrix_to_quat, quat_to_matrix, wxyz_to_xyzw, xyzw_to_wxyz
from . import topics


def tension_top(desc) -> float:
    """Top of the tension colour scale, N: the weight of the nominal platform shared by four
    cables, times two (2 m g / 4); 1000 N when the mass is not described."""
    m = desc.cdpr.platform_mass
    return 0.5 * m * desc.gravity if m else 1000.0


def cdpr_markers(desc, position, R, tensions=None) -> list[Marker]:
    """Markers of one pose: ``position`` (3,) and ``R`` (3, 3) of the platform in ``world``,
    ``tensions`` (n,) N or None (grey cables)."""
    c = desc.cdpr
    A = c.exit_points
    B = np.asarray(position, float) + c.anchor_points @ np.asarray(R, float).T
    if tensions is None:
        colours = np.tile([0.6, 0.6, 0.6, 1.0], (len(A), 1))
    else:
        colours = tension_colour(tensions, tension_top(desc))
    out = [line("cables", i + 1, [A[i], B[i]], colours[i]) for i in range(len(A))]
    lo, hi = c.anchor_points.min(axis=0), c.anchor_points.max(axis=0)
    centre = np.asarray(position, float) + np.asarray(R, float) @ (0.5 * (lo + hi))
    size = np.maximum(hi - lo, 0.05)
    out.append(Marker(CUBE, "platform", 0, tuple(centre), tuple(wxyz_to_xyzw(matrix_to_quat(R))),
                      tuple(size), (0.3, 0.3, 0.35, 0.8)))
    out.append(Marker(SPHERE_LIST, "exit_points", 0, scale=(0.08, 0.08, 0.08),
                      colour=(0.9, 0.6, 0.1, 1.0), points=A))
    # the frame: each exit point joined to its nearest neighbour (each pair once)
    d = np.linalg.norm(A[:, None, :] - A[None, :, :], axis=2) + np.diag(np.full(len(A), np.inf))
    pairs = sorted({tuple(sorted((i, int(j)))) for i, j in enumerate(np.argmin(d, axis=1))})
    out.append(Marker(LINE_LIST, "frame", 0, scale=(0.03, 0.0, 0.0), colour=(0.5, 0.5, 0.5, 1.0),
                      points=np.array([A[k] for pair in pairs for k in pair])))
    return out


def sim_markers(desc, sim) -> list[Marker]:
    """The simulator's 3D view: the platform at the true pose of ``sim``
    (:class:`~.sim.CdprSim`), the cables coloured by their true tension."""
    p, q = sim.truth_pose()
    return cdpr_markers(desc, p, quat_to_matrix(q), sim.truth_state()["tension"])


def bag_markers(bag, desc):
    """``(t, frames)`` at about 30 Hz along a recording: the measured platform pose (else the
    ground truth, else the reference), the dynamometer tensions when recorded; None without a
    pose."""
    pose = None
    for topic in (topics.PLATFORM_POSE, topics.GROUND_TRUTH_POSE):
        if bag.has(topic) and bag.counts.get(topic):
            s = bag.pose(topic)
            pose = (s.t, s.position, s.quaternion)
            break
    if pose is None and bag.has(topics.REFERENCE) and bag.counts.get(topics.REFERENCE):
        s = bag.multidof_trajectory(topics.REFERENCE)
        pose = (s.t, s.position, s.quaternion)
    if pose is None or desc is None or desc.cdpr is None:
        return None
    t, p, q = pose
    keep = decimate_times(t)
    t, p, R = t[keep], p[keep], quat_to_matrix(xyzw_to_wxyz(q[keep]))
    ten = None
    if bag.has(topics.CABLE_TENSIONS) and bag.counts.get(topics.CABLE_TENSIONS):
        s = bag.joint_state(topics.CABLE_TENSIONS, [f"cable_{i}" for i in range(1, len(desc.cdpr.cables) + 1)])
        ten = np.stack([np.interp(t, s.t, s.effort[:, i]) for i in range(s.effort.shape[1])], axis=1)
    frames = [cdpr_markers(desc, p[k], R[k], None if ten is None else ten[k]) for k in range(len(t))]
    return t, frames
