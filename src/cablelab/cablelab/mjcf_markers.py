"""Markers (:mod:`cablelab.markers`) of any MuJoCo model: its geoms as shapes and its spatial
tendons as lines, in the model's world frame, for a plant whose machine is an MJCF file.

:func:`model_markers` reads one state (``MjData`` after ``mj_forward`` or ``mj_kinematics``):

* every visible geom (alpha > 0) as a shape at ``geom_xpos`` turned by ``geom_xmat``: box ->
  CUBE (scale = 2 x half sizes), sphere -> SPHERE, ellipsoid -> SPHERE scaled per axis, cylinder
  -> CYLINDER (the axis of both is z), capsule -> CYLINDER plus two SPHERE caps (ns
  ``geom_caps``), plane -> a thin CUBE (10 m a side when infinite), mesh / height field / SDF ->
  the CUBE of its bounding box (``geom_aabb``); colour ``geom_rgba`` (the material's when it has
  one);
* every spatial tendon as a LINE_LIST through its path (``wrap_xpos`` from ``ten_wrapadr`` over
  ``ten_wrapnum`` points): one segment per pair of consecutive points of a branch, a pulley
  starting a new branch. The number of path points changes when a wrapping geom is touched or
  left, so each tendon's list is padded to the most points its path can have (zero-length
  segments at its last point): one model gives one layout, which
  :class:`cablelab.markers.MarkerEncoder` and the simulators' timers need. Colour: by
  ``tendon_force`` (N, :func:`cablelab.markers.tension_colour` up to ``top``) when given, else
  ``tendon_rgba``; :func:`tendon_tension` gives the force of a state.

ns ``geoms`` / ``tendons``, id = the geom / tendon index, so a Foxglove user finds an element by
the index MuJoCo gives it.
"""
from __future__ import annotations

import mujoco
import numpy as np

from .markers import CUBE, CYLINDER, LINE_LIST, SPHERE, Marker, tension_colour

#: side of the square drawn for an infinite plane, m
PLANE_SIZE = 10.0
# plain ints: a numpy integer compares equal to these enums but ``in`` a tuple of them it is not
_BOX, _SPHERE, _ELLIPSOID, _CYLINDER, _CAPSULE, _PLANE = (
    int(getattr(mujoco.mjtGeom, f"mjGEOM_{n}")) for n in ("BOX", "SPHERE", "ELLIPSOID", "CYLINDER", "CAPSULE", "PLANE"))
_WRAP_JOINT, _WRAP_SPHERE, _WRAP_CYLINDER = (
    int(getattr(mujoco.mjtWrap, f"mjWRAP_{n}")) for n in ("JOINT", "SPHERE", "CYLINDER"))


def tendon_capacity(model: mujoco.MjModel) -> np.ndarray:
    """Most path points each tendon can have (0 for a fixed tendon): one per site and pulley,
    two per wrapping geom (the tangent points)."""
    out = np.zeros(model.ntendon, dtype=int)
    for t in range(model.ntendon):
        adr, num = model.tendon_adr[t], model.tendon_num[t]
        types = model.wrap_type[adr:adr + num]
        if num and int(types[0]) != _WRAP_JOINT:
            out[t] = num + int(np.isin(types, (_WRAP_SPHERE, _WRAP_CYLINDER)).sum())
    return out


def tendon_paths(model: mujoco.MjModel, data: mujoco.MjData) -> list[list[np.ndarray]]:
    """Per tendon its branches, each a (k, 3) array of path points in world (empty list for a
    fixed tendon)."""
    obj = data.wrap_obj.reshape(-1)
    xpos = data.wrap_xpos.reshape(-1, 3)
    cap = tendon_capacity(model)
    out = []
    for t in range(model.ntendon):
        if not cap[t]:
            out.append([])
            continue
        adr, num = data.ten_wrapadr[t], data.ten_wrapnum[t]
        o, p = obj[adr:adr + num], xpos[adr:adr + num]
        cut = np.flatnonzero(o == -2)               # a pulley: the next branch starts after it
        bounds = np.r_[-1, cut, num]
        out.append([p[a + 1:b].copy() for a, b in zip(bounds[:-1], bounds[1:]) if b - a > 1])
    return out


def tendon_tension(model: mujoco.MjModel, data: mujoco.MjData) -> np.ndarray:
    """(ntendon,) pulling force along each tendon, N, of a state after ``mj_forward``: the
    actuators acting on it (``actuator_force`` x gear, a force that lengthens the tendon counted
    negative), its limit constraint (``efc_force`` of its ``LIMIT_TENDON`` row: pulling at the
    upper end of the range, pushing at the lower) and its passive spring-damper
    (``tendon_stiffness`` beyond ``tendon_lengthspring``, ``tendon_damping`` x velocity)."""
    f = np.zeros(model.ntendon)
    on = np.flatnonzero(model.actuator_trntype == int(mujoco.mjtTrn.mjTRN_TENDON))
    np.add.at(f, model.actuator_trnid[on, 0], -data.actuator_force[on] * model.actuator_gear[on, 0])
    n = data.nefc
    rows = np.flatnonzero(data.efc_type[:n] == int(mujoco.mjtConstraint.mjCNSTR_LIMIT_TENDON))
    t = data.efc_id[rows]
    L, lo, hi = data.ten_length[t], model.tendon_range[t, 0], model.tendon_range[t, 1]
    np.add.at(f, t, np.where(np.abs(L - hi) <= np.abs(L - lo), 1.0, -1.0) * data.efc_force[rows])
    L, (lo, hi) = data.ten_length, model.tendon_lengthspring.T
    stretch = np.where(L > hi, L - hi, np.where(L < lo, L - lo, 0.0))
    return f + model.tendon_stiffness * stretch + model.tendon_damping * data.ten_velocity


def _segments(branches: list[np.ndarray], capacity: int) -> np.ndarray:
    """(2 (capacity - 1), 3) LINE_LIST points of ``branches``, padded at the last point."""
    pts = [np.stack([b[:-1], b[1:]], axis=1).reshape(-1, 3) for b in branches if len(b) > 1]
    seg = np.concatenate(pts) if pts else np.zeros((0, 3))
    n = 2 * max(capacity - 1, 1)
    last = seg[-1] if len(seg) else (branches[0][-1] if branches and len(branches[0]) else np.zeros(3))
    return np.concatenate([seg, np.tile(last, (n - len(seg), 1))])[:n]


def model_markers(model: mujoco.MjModel, data: mujoco.MjData, tendon_force=None,
                  top: float = 1.0) -> list[Marker]:
    """Markers of the state in ``data`` (module docstring). ``tendon_force``: (ntendon,) N or
    None; ``top``: force at the red end of the colour scale."""
    out: list[Marker] = []
    rgba = model.geom_rgba.copy()
    mat = model.geom_matid
    rgba[mat >= 0] = model.mat_rgba[mat[mat >= 0]]
    R = data.geom_xmat.reshape(-1, 3, 3)
    quat = np.zeros((model.ngeom, 4))
    for g in range(model.ngeom):      # MuJoCo's own conversion (exact at 180 degree turns too)
        mujoco.mju_mat2Quat(quat[g], data.geom_xmat[g])
    quat = quat[:, [1, 2, 3, 0]]                         # (w, x, y, z) -> (x, y, z, w)
    for g in range(model.ngeom):
        if rgba[g, 3] <= 0:
            continue
        typ, size, pos, q = int(model.geom_type[g]), model.geom_size[g], data.geom_xpos[g], quat[g]
        col = tuple(float(c) for c in rgba[g])
        if typ == _BOX:
            out.append(Marker(CUBE, "geoms", g, tuple(pos), tuple(q), tuple(2 * size), col))
        elif typ in (_SPHERE, _ELLIPSOID):
            s = 2 * (size[[0, 0, 0]] if typ == _SPHERE else size)
            out.append(Marker(SPHERE, "geoms", g, tuple(pos), tuple(q), tuple(s), col))
        elif typ in (_CYLINDER, _CAPSULE):
            r, h = size[0], size[1]
            out.append(Marker(CYLINDER, "geoms", g, tuple(pos), tuple(q), (2 * r, 2 * r, 2 * h), col))
            if typ == _CAPSULE:
                for k, sgn in enumerate((1.0, -1.0)):
                    out.append(Marker(SPHERE, "geom_caps", 2 * g + k, tuple(pos + sgn * h * R[g][:, 2]), tuple(q),
                                      (2 * r,) * 3, col))
        elif typ == _PLANE:
            sx, sy = (2 * s if s > 0 else PLANE_SIZE for s in size[:2])
            out.append(Marker(CUBE, "geoms", g, tuple(pos), tuple(q), (sx, sy, 0.001), col))
        else:                                           # mesh, height field, SDF: bounding box
            centre, half = model.geom_aabb[g, :3], model.geom_aabb[g, 3:]
            out.append(Marker(CUBE, "geoms", g, tuple(pos + R[g] @ centre), tuple(q), tuple(2 * half), col))
    cap = tendon_capacity(model)
    paths = tendon_paths(model, data)
    colours = (tension_colour(np.asarray(tendon_force, float), top) if tendon_force is not None
               else model.tendon_rgba)
    for t in range(model.ntendon):
        if not cap[t]:
            continue
        width = float(model.tendon_width[t])
        out.append(Marker(LINE_LIST, "tendons", t, scale=(2 * width, 0.0, 0.0),
                          colour=tuple(float(c) for c in colours[t]), points=_segments(paths[t], cap[t])))
    return out


__all__ = ["PLANE_SIZE", "model_markers", "tendon_capacity", "tendon_paths", "tendon_tension"]
