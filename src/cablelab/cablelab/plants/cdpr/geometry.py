"""CDPR geometry: inverse geometric model and wrench matrix, without and with pulleys (001 sec. III).

Model I (001 eq. 1-5) treats each pulley as the fixed point A_i; Model II (001 eq. 6-9, CONTRACT
section 3) follows the cable over a 2-DoF swivel pulley of sheave radius r_p:

* the sheave turns about the swivel axis z_s through A_i so that its plane contains B_i;
* its centre is O_i = A_i + r_p x_p, with x_p the unit vector from A_i towards B_i perpendicular
  to z_s (001 eq. 6);
* the cable arrives from the winch travelling along +z_s, touches the sheave at A_i (the rim
  point on the swivel axis at axle height), wraps over it and leaves at the tangent point A'_i
  towards B_i. The wrap angle is beta_i and the free segment A'_i -> B_i has length l_ci
  (001 eq. 8-9).

Everything is vectorised over time: poses are ``(N, 3)`` positions with optional ``(N, 3, 3)``
rotation matrices (platform frame -> world), and results are ``(N, n)`` / ``(N, n, 3)`` arrays
for the n cables. Lengths in m, angles in rad.
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from ...rotations import cross, matrix_to_quat, quat_to_matrix

__all__ = [
    "CableGeometry", "cable_geometry", "wrench_matrix", "cable_wrench", "quat_to_matrix",
    "matrix_to_quat", "cross", "swivel_reference", "pose_geometry",
]


@dataclass(frozen=True)
class CableGeometry:
    """Per-sample cable geometry (N samples, n cables).

    Attributes:
        directions: (N, n, 3) unit vectors along each cable from the anchor B_i towards the
            pulley (u_i of 001 eq. 2 for Model I, e_i of 001 eq. 8 for Model II); a tension t_i
            pulls the platform with force t_i * directions[:, i].
        lengths: (N, n) cable length from A_i to B_i, m (Model I: |A_i B_i|; Model II:
            r_p * beta_i + l_ci, the part on the sheave plus the free segment).
        anchors: (N, n, 3) anchor vectors R b_i in world axes (from the platform origin P), m.
        free_lengths: (N, n) length of the straight free segment (l_ci; Model I: lengths), m.
        wrap_angles: (N, n) angle of sheave wrapped by the cable, rad (0 for Model I).
        swivel_angles: (N, n) pulley swivel angle about its axis from the reference direction
            of :func:`swivel_reference` (atan2 to the anchor), rad.
        tangent_points: (N, n, 3) exit points A'_i in world (A_i for Model I), m.
    """

    directions: np.ndarray
    lengths: np.ndarray
    anchors: np.ndarray
    free_lengths: np.ndarray
    wrap_angles: np.ndarray
    swivel_angles: np.ndarray
    tangent_points: np.ndarray


def swivel_reference(axes: np.ndarray) -> np.ndarray:
    """(n, 3) zero direction of each swivel angle: world x projected normal to the axis
    (world y when the axis is along x)."""
    axes = np.asarray(axes, dtype=float)
    ref = np.where(np.abs(axes[:, :1]) > 0.9, [[0.0, 1.0, 0.0]], [[1.0, 0.0, 0.0]])
    ref = ref - np.sum(ref * axes, -1, keepdims=True) * axes
    return ref / np.linalg.norm(ref, axis=-1, keepdims=True)


def _swivel_plane(exit_points, anchor_points, position, rotation, swivel_axes):
    """Anchors in world and each cable's swivel plane: (A, B, R b, z, d = B - A, its part dz
    along the swivel axis, the distance h normal to it, the in-plane unit x_p of 001 eq. 6)."""
    A = np.asarray(exit_points, dtype=float)
    b = np.asarray(anchor_points, dtype=float)
    p = np.atleast_2d(np.asarray(position, dtype=float))
    n = A.shape[0]
    if rotation is None:
        bw = np.broadcast_to(b, (p.shape[0], n, 3))
    else:
        Rm = np.asarray(rotation, dtype=float)
        if Rm.ndim == 2:
            Rm = Rm[None]
        bw = np.einsum("tij,nj->tni", Rm, b)
    B = p[:, None, :] + bw                                   # (N, n, 3) anchors in world
    z = np.broadcast_to([0.0, 0.0, 1.0], (n, 3)) if swivel_axes is None else np.asarray(swivel_axes, float)
    d = B - A                                                # A_i -> B_i
    dz = np.einsum("tni,ni->tn", d, z)
    dh = d - dz[..., None] * z                               # part normal to the swivel axis
    h = np.sqrt(np.einsum("tni,tni->tn", dh, dh))
    xp = dh / np.maximum(h, 1e-12)[..., None]                # x_p of 001 eq. 6
    return A, B, bw, z, d, dz, h, xp


def check_pulley_radius(exit_points, anchor_points, position, rotation, pulley_radius: float,
                        swivel_axes=None, where: str = "cdpr.pulley_radius") -> None:
    """A sheave of radius r_p must leave every cable a tangent: the attachment point B_i must stay
    farther than r_p from the sheave centre O_i = A_i + r_p x_p in every pose (else Model II has no
    solution and every sample is lost). One-line :class:`~cablelab.errors.CablelabError` naming
    the radius, the cable and the largest radius the poses allow otherwise."""
    from ...errors import CablelabError

    r = float(pulley_radius)
    if r <= 0:
        return
    _, _, _, _, _, dz, h, _ = _swivel_plane(exit_points, anchor_points, position, rotation, swivel_axes)
    # (h - r)^2 + dz^2 > r^2  <=>  r < (h^2 + dz^2) / (2 h): the largest radius of each pose
    largest = (h * h + dz * dz) / np.maximum(2.0 * h, 1e-300)
    if np.all(r < largest):
        return
    k, i = np.unravel_index(int(np.argmin(largest)), largest.shape)
    hint = f"; these poses allow at most {float(largest[k, i]):.3g} m"
    raise CablelabError(f"{where}: {r:g} m is larger than the geometry allows: cable {i + 1}'s "
                        f"attachment comes within {float(np.hypot(h[k, i] - r, dz[k, i])):.3g} m of its sheave centre "
                        f"(sample {k}), so no cable leaves the sheave tangentially{hint}")


def cable_geometry(exit_points: np.ndarray, anchor_points: np.ndarray, position: np.ndarray,
                   rotation: np.ndarray | None = None, pulley_radius: float = 0.0,
                   swivel_axes: np.ndarray | None = None) -> CableGeometry:
    """Inverse geometric model of a CDPR, Model I (``pulley_radius == 0``) or Model II.

    Args:
        exit_points: (n, 3) A_i in world, m.
        anchor_points: (n, 3) B_i in the platform frame, m.
        position: (N, 3) or (3,) platform origin P in world, m.
        rotation: (N, 3, 3) or (3, 3) platform -> world rotation; None = level platform.
        pulley_radius: sheave radius r_p, m (001 eq. 6); 0 gives Model I (001 eq. 1-2).
        swivel_axes: (n, 3) unit swivel axes; default +z.

    Returns:
        :class:`CableGeometry` (arrays with a leading sample axis N; N = 1 for a single pose).
    """
    A, B, bw, z, d, dz, h, xp = _swivel_plane(exit_points, anchor_points, position, rotation, swivel_axes)
    ref = swivel_reference(z)
    swivel = np.arctan2(np.einsum("tni,ni->tn", xp, cross(z, ref)), np.einsum("tni,ni->tn", xp, ref))
    r = float(pulley_radius)
    if r <= 0.0:
        L = np.sqrt(h * h + dz * dz)
        u = -d / L[..., None]
        zeros = np.zeros_like(L)
        return CableGeometry(u, L, bw, L, zeros, swivel, np.broadcast_to(A, B.shape).copy())
    # Model II: in-plane coordinates of B relative to the sheave centre O = A + r x_p
    vx = h - r
    vz = dz
    D2 = vx * vx + vz * vz
    lc = np.sqrt(np.maximum(D2 - r * r, 0.0))                # tangent segment l_ci
    # radial unit vector to the tangent point: rotate (vx, vz)/|v| by +acos(r/|v|) in the plane
    cx = (r * vx - lc * vz) / D2
    cz = (r * vz + lc * vx) / D2
    phi = np.arctan2(cz, cx)                                 # angle of A' from x_p
    beta = np.pi - phi                                       # wrap from the rim point A (at angle pi)
    Ap = A + (r * (1.0 + cx))[..., None] * xp + (r * cz)[..., None] * z
    e = (Ap - B) / lc[..., None]                             # e_i of 001 eq. 8, from B_i to A'_i
    return CableGeometry(e, r * beta + lc, bw, lc, beta, swivel, Ap)


def wrench_matrix(geom: CableGeometry) -> np.ndarray:
    """(N, 6, n) wrench matrix W of 001 eq. 4 (Model I) or eq. 7 (Model II): columns
    [d_i; (R b_i) x d_i], forces in N and moments in N m about the platform origin, world axes."""
    d = geom.directions
    return np.concatenate([d, cross(geom.anchors, d)], axis=-1).transpose(0, 2, 1)


def cable_wrench(geom: CableGeometry, tensions: np.ndarray) -> np.ndarray:
    """(N, 6) wrench W t applied by the cables (001 eq. 3, 12), without forming W.

    Args:
        geom: geometry of N samples.
        tensions: (N, n) cable tensions, N.
    """
    f = geom.directions * np.asarray(tensions, dtype=float)[..., None]
    return np.concatenate([f.sum(1), cross(geom.anchors, f).sum(1)], axis=-1)


def pose_geometry(exit_points: np.ndarray, anchor_points: np.ndarray, position: np.ndarray,
                  rotation: np.ndarray | None = None, pulley_radius: float = 0.0,
                  swivel_axes: np.ndarray | None = None):
    """One pose, fast (live nodes at 1 kHz): the same directions and lengths as
    :func:`cable_geometry` for a single pose, on (n,) arrays without the batch machinery. A
    ``position`` of shape (N, 1, 3) (and no rotation) gives N poses at once, the same arithmetic
    broadcast: ``(N, n, 3)`` directions and ``(N, n)`` lengths.

    Returns:
        ``(directions (n, 3), lengths (n,), anchors (n, 3))`` as in :class:`CableGeometry`.
    """
    A = exit_points
    bw = anchor_points if rotation is None else anchor_points @ np.asarray(rotation).T
    d = position + bw - A
    r = float(pulley_radius)
    if r <= 0.0:
        L = np.sqrt((d * d).sum(-1))
        return -d / L[..., None], L, bw
    z = swivel_axes
    dz = (d * z).sum(-1)
    hv = d - dz[..., None] * z
    h = np.sqrt((hv * hv).sum(-1))
    vx = h - r
    D2 = vx * vx + dz * dz
    lc = np.sqrt(D2 - r * r)
    cx = (r * vx - lc * dz) / D2
    cz = (r * dz + lc * vx) / D2
    e = ((r * (1.0 + cx) / h)[..., None] * hv + (r * cz)[..., None] * z - d) / lc[..., None]
    return e, r * (np.pi - np.arctan2(cz, cx)) + lc, bw
