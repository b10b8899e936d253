"""The boom crane in 3D (:mod:`cablelab.markers`): mast, boom from the luff pivot (the origin of
``world``) to the boom tip, rope from the tip to the payload, the payload and the counterbalance
behind the pivot when described."""
from __future__ import annotations

import numpy as np

from ...markers import SPHERE, Marker, decimate_times, line
from . import topics
from .kinematics import boom_tip


def crane_markers(desc, tip, payload, alpha: float) -> list[Marker]:
    """Markers of one state: boom tip and payload positions (3,) in ``world``, slew angle alpha."""
    tip, payload = np.asarray(tip, float), np.asarray(payload, float)
    lb = desc.crane.boom_length
    out = [line("mast", 0, [[0.0, 0.0, -lb], [0.0, 0.0, 0.0]], (0.4, 0.4, 0.4, 1.0), 0.05),
           line("boom", 0, [[0.0, 0.0, 0.0], tip], (0.9, 0.6, 0.1, 1.0), 0.04),
           line("rope", 0, [tip, payload], (0.2, 0.2, 0.2, 1.0), 0.01)]
    r = 0.08 * lb
    out.append(Marker(SPHERE, "payload", 0, tuple(payload), scale=(r, r, r), colour=(0.2, 0.4, 0.9, 1.0)))
    cb = desc.crane.counterbalance
    if cb is not None:
        p = -cb.distance * np.array([np.cos(alpha), np.sin(alpha), 0.0])
        out.append(Marker(SPHERE, "counterbalance", 0, tuple(p), scale=(0.1 * lb,) * 3,
                          colour=(0.5, 0.5, 0.5, 1.0)))
    return out


def bag_markers(bag, desc):
    """``(t, frames)`` at about 30 Hz: the recorded boom-tip and payload poses (motion capture)
    and the slew angle; None when the bag lacks them."""
    need = (topics.TIP_POSE, topics.PAYLOAD_POSE, topics.JOINT_STATES)
    if desc is None or desc.crane is None or not all(bag.has(t) and bag.counts.get(t) for t in need):
        return None
    tip = bag.pose(need[0])
    pay = bag.pose(need[1])
    js = bag.joint_state(need[2], ["slew", "luff", "hoist"])
    t = tip.t[decimate_times(tip.t)]
    P = np.stack([np.interp(t, pay.t, pay.position[:, i]) for i in range(3)], axis=1)
    T = np.stack([np.interp(t, tip.t, tip.position[:, i]) for i in range(3)], axis=1)
    alpha = np.interp(t, js.t, js.position[:, 0])
    ok = np.isfinite(P).all(axis=1) & np.isfinite(T).all(axis=1)
    t, P, T, alpha = t[ok], P[ok], T[ok], alpha[ok]
    return t, [crane_markers(desc, T[k], P[k], alpha[k]) for k in range(len(t))]


def state_markers(desc, q) -> list[Marker]:
    """Markers of a simulator state q = [alpha, beta, d, theta1, theta2]."""
    from .kinematics import payload_position

    lb = desc.crane.boom_length
    tip = boom_tip(q[0], q[1], lb)
    return crane_markers(desc, tip, payload_position(q[0], q[1], q[2], q[3], q[4], lb), q[0])
