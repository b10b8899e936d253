"""Any machine in 3D (:mod:`cablelab.markers`): the model's own geoms and spatial tendons drawn by
:func:`cablelab.mjcf_markers.model_markers`, in the model's world frame (``world``).

Live (:func:`sim_markers`): the simulator's MuJoCo state, tendons coloured by their tension.
From a recording (:func:`bag_markers`): the recorded joint positions put into the description's
model (``mj_fwdPosition``: body, geom and tendon-path positions), tendons coloured by the
recorded tensions of the measured tendons when the bag has them.
"""
from __future__ import annotations

import numpy as np

from ...markers import Marker, decimate_times
from ...mjcf_markers import model_markers, tendon_tension
from .description import section_of
from .mjcf import dof_joints, names
from .topics import topic


def _top(model, tension: np.ndarray) -> float:
    """Force at the red end of the colour scale: the largest of the tendon's force limits, else
    twice the largest tension drawn, at least 1 N."""
    limits = np.abs(model.tendon_range[:, 1]) if model.ntendon else np.zeros(0)
    finite = np.asarray(tension, float)[np.isfinite(tension)] if np.size(tension) else np.zeros(0)
    return float(max(1.0, 2.0 * np.abs(finite).max() if finite.size else 0.0,
                     limits.max() if limits.size and np.isfinite(limits).all() else 0.0))


def sim_markers(sim, top: float | None = None) -> list[Marker]:
    """Markers of a running :class:`~.sim.MjcfSim`'s state (tendons coloured by tension)."""
    force = tendon_tension(sim.model, sim.data)
    return model_markers(sim.model, sim.data, force, top or _top(sim.model, force))


def bag_markers(bag, desc):
    """``(t, frames)`` at about 30 Hz from the recorded joint positions; None when the bag or
    the description lacks them."""
    import mujoco

    sec = section_of(desc) if desc is not None else None
    if sec is None:
        return None
    js_topic = topic(sec, "joint_states")
    if not (bag.has(js_topic) and bag.counts.get(js_topic)):
        return None
    model = sec.compiled(desc.gravity)
    joints = dof_joints(model)
    js = bag.joint_state(js_topic)
    if not js.position.size or any(j not in js.names for j in joints):
        return None
    q = js.position[:, [js.names.index(j) for j in joints]]
    keep = decimate_times(js.t)
    keep = keep[np.isfinite(q[keep]).all(axis=1)]
    jn = names(model, "joint")
    adr = np.array([model.jnt_qposadr[jn.index(j)] for j in joints], dtype=int)
    tension_at = _recorded_tensions(bag, sec, model, js.t[keep])
    data = mujoco.MjData(model)
    frames = []
    for i, k in enumerate(keep):
        data.qpos[adr] = q[k]
        mujoco.mj_fwdPosition(model, data)
        force = tension_at[i] if tension_at is not None else None
        frames.append(model_markers(model, data, force, _top(model, tension_at) if force is not None else 1.0))
    return js.t[keep], frames


def _recorded_tensions(bag, sec, model, t: np.ndarray):
    """(len(t), ntendon) measured tensions at ``t`` (nearest earlier sample; unmeasured tendons
    0), or None without a cable_tensions topic."""
    ct = topic(sec, "cable_tensions")
    if not sec.tendons or not (bag.has(ct) and bag.counts.get(ct)):
        return None
    s = bag.joint_state(ct)
    if not s.effort.size:
        return None
    out = np.zeros((len(t), model.ntendon))
    tn = names(model, "tendon")
    i = np.clip(np.searchsorted(s.t, t, side="right") - 1, 0, len(s.t) - 1)
    for name in sec.tendons:
        if name in s.names:
            out[:, tn.index(name)] = s.effort[i, s.names.index(name)]
    return out
