"""The cable-suspended platform in 3D (:mod:`cablelab.markers`), frame ``world``.

The cables coloured by tension (blue 0 to red at twice each cable's share of the hanging
weight): LiCAS hangs by four cables from S + (+-s/2, +-s/2, 0) to the platform's corners
(+-s/2, +-s/2, 0) (the truth plant of :mod:`.mjcf`, s = :data:`~.mjcf.CABLE_SEPARATION`),
CRANEbot by one rope from S to the platform's attachment point; the platform (a box turned with
it); both arms as lines through their joints to the last link's centre of mass, by the forward
kinematics of the parameter set's arm chain (joint origins, axes; the right arm mirrors y) at
the measured joint angles.

Tensions from a MuJoCo state (:func:`cable_tensions`): the four tendons' tensions of the LiCAS
truth plant (:func:`cablelab.mjcf_markers.tendon_tension`), or the force the cable link passes to the platform link (``cfrc_int`` of
``link10`` along the cable) in the virtual-joint models, shared by the drawn cables.
"""
from __future__ import annotations

import mujoco
import numpy as np

from ...markers import CUBE, Marker, decimate_times, line, tension_colour
from ...mjcf_markers import tendon_tension
from ...rotations import matrix_to_quat, quat_to_matrix, wxyz_to_xyzw, xyzw_to_wxyz
from .mjcf import CABLE_SEPARATION, arm_joint_names
from .params import VirtualParams

POSE, JOINTS = "/suspended/platform_pose", "/suspended/joint_states"
_CORNERS = np.array([(1, 1, 0), (-1, 1, 0), (-1, -1, 0), (1, -1, 0)], float) * CABLE_SEPARATION / 2


def _turn(axis: str, q: float) -> np.ndarray:
    c, s = np.cos(q), np.sin(q)
    i = "xyz".index(axis)
    j, k = (i + 1) % 3, (i + 2) % 3
    R = np.eye(3)
    R[j, j], R[j, k], R[k, j], R[k, k] = c, -s, s, c
    return R


def arm_points(p: VirtualParams, pos, R, q) -> np.ndarray:
    """(2, n + 1, 3): per arm (left, right) its joint origins and the last link's centre of mass
    in world, for platform position ``pos`` (the attachment point), rotation ``R`` and arm angles
    ``q`` (2n,) in :func:`~.mjcf.arm_joint_names` order."""
    n = p.n_arm
    out = np.empty((2, n + 1, 3))
    for side, s in enumerate((1.0, -1.0)):
        x, Rk = np.asarray(pos, float), np.asarray(R, float)
        mirror = np.array([1.0, s, 1.0])
        for i, a in enumerate(p.arm):
            x = x + Rk @ ((np.asarray(p.arm_mount) if i == 0 else np.asarray(a.pos)) * mirror)
            Rk = Rk @ _turn(a.axis, q[side * n + i])
            out[side, i] = x
        out[side, n] = x + Rk @ (np.asarray(p.arm[-1].com) * mirror)
    return out


def cable_count(p: VirtualParams) -> int:
    return 4 if p.variant == "licas" else 1


def suspended_markers(p: VirtualParams, pos, R, q, tensions=None) -> list[Marker]:
    """Markers of one state: platform attachment point ``pos`` (3,), rotation ``R`` (3, 3), arm
    angles ``q`` (2n,), cable tensions (N, one per cable) or None (grey)."""
    pos, R = np.asarray(pos, float), np.asarray(R, float)
    S = np.asarray(p.S, float)
    if cable_count(p) == 4:
        ends = np.stack([S + _CORNERS, pos + _CORNERS @ R.T], axis=1)
    else:
        ends = np.array([[S, pos]])
    weight = (p.m_plat + 2 * sum(a.mass for a in p.arm)) * 9.81
    colours = (np.tile([0.6, 0.6, 0.6, 1.0], (len(ends), 1)) if tensions is None else
               tension_colour(tensions, 2.0 * weight / len(ends)))
    out = [line("cables", i + 1, ends[i], colours[i], 0.01) for i in range(len(ends))]
    side = CABLE_SEPARATION + 0.05
    out.append(Marker(CUBE, "platform", 0, tuple(pos + R @ np.asarray(p.c_plat, float)),
                      tuple(wxyz_to_xyzw(matrix_to_quat(R))), (side, side, 0.04), (0.3, 0.3, 0.35, 0.8)))
    arms = arm_points(p, pos, R, q)
    out += [line("arms", k, arms[k], (0.9, 0.6, 0.1, 1.0), 0.02) for k in range(2)]
    return out


def cable_tensions(p: VirtualParams, model: mujoco.MjModel, data: mujoco.MjData) -> np.ndarray:
    """Tension of each drawn cable (N) of a MuJoCo state after ``mj_forward`` (module docstring)."""
    n = cable_count(p)
    tendons = {model.tendon(i).name for i in range(model.ntendon)}
    if n == 4 and {f"cable{i}" for i in range(4)} <= tendons:
        ten = tendon_tension(model, data)
        return np.array([ten[model.tendon(f"cable{i}").id] for i in range(4)])
    mujoco.mj_rnePostConstraint(model, data)
    b = model.body("link10").id
    u = data.site_xpos[model.site("S").id] - data.xpos[b]
    u /= max(np.linalg.norm(u), 1e-12)
    return np.full(n, float(data.cfrc_int[b, 3:] @ u) / n)


def state_markers(p: VirtualParams, model: mujoco.MjModel, data: mujoco.MjData) -> list[Marker]:
    """Markers of a simulator's MuJoCo state (platform pose from its sensors, arm angles from
    ``qpos``, tensions from :func:`cable_tensions`)."""
    q = [data.qpos[model.joint(j).qposadr[0]] for j in arm_joint_names(p)]
    return suspended_markers(p, data.sensordata[:3], quat_to_matrix(data.sensordata[3:7]), q,
                             cable_tensions(p, model, data))


def bag_markers(bag, desc):
    """``(t, frames)`` at about 30 Hz from the recorded platform pose and arm joint angles (grey
    cables: a recording holds no tension); None without a pose."""
    sec = getattr(desc, "suspended", None) if desc is not None else None
    if sec is None or not (bag.has(POSE) and bag.counts.get(POSE)):
        return None
    p = sec.params()
    pose = bag.pose(POSE)
    ok = np.isfinite(pose.position).all(axis=1) & np.isfinite(pose.quaternion).all(axis=1)
    t, pos, quat = pose.t[ok], pose.position[ok], pose.quaternion[ok]
    keep = decimate_times(t)
    t, pos, R = t[keep], pos[keep], quat_to_matrix(xyzw_to_wxyz(quat[keep]))
    names = list(arm_joint_names(p))
    q = np.zeros((len(t), len(names)))
    if bag.has(JOINTS) and bag.counts.get(JOINTS):
        js = bag.joint_state(JOINTS, names)
        q = np.stack([np.interp(t, js.t, np.nan_to_num(js.position[:, i])) for i in range(len(names))], axis=1)
    return t, [suspended_markers(p, pos[k], R[k], q[k]) for k in range(len(t))]
