"""The crane's offline swing estimate from a bag (``cablelab estimate``, CONTRACT sec. 5)."""
from __future__ import annotations

import numpy as np

from ...errors import CablelabError
from .dataset import SWING_NAMES
from .topics import (JOINT_STATE, JOINT_STATES, PAYLOAD_POSE, POSE, SWING_ESTIMATE, SWING_TRUTH,
                     TIP_POSE)
from .kinematics import SwingAngles
from .swing import SwingReport, estimate_swing


def swing_from_bag(bag, *, cutoff_hz: float | None = None) -> tuple[SwingAngles, SwingReport]:
    """Swing estimate over a bag: motion-capture poses + slew angle of ``/crane/joint_states``."""
    for topic, typ in ((JOINT_STATES, JOINT_STATE), (TIP_POSE, POSE), (PAYLOAD_POSE, POSE)):
        bag.require(topic, typ)
    js = bag.joint_state(JOINT_STATES, ["slew"])
    tip = bag.pose(TIP_POSE)
    pay = bag.pose(PAYLOAD_POSE)
    if tip.t.shape != pay.t.shape or not np.array_equal(tip.t, pay.t, equal_nan=True):
        # different stamps: bring the payload onto the tip stamps (NaN outside its range)
        ok = np.isfinite(pay.t) & np.isfinite(pay.position).all(1)
        if ok.sum() < 2:
            raise CablelabError(f"{bag.path}: {PAYLOAD_POSE} has fewer than 2 finite poses")
        order = np.argsort(pay.t[ok])
        tp = pay.t[ok][order]
        pos = np.column_stack([np.interp(tip.t, tp, pay.position[ok][order][:, i], left=np.nan,
                                         right=np.nan) for i in range(3)])
    else:
        pos = pay.position
    return estimate_swing(tip.t, tip.position, pos, js.t, js.position[:, 0], cutoff_hz=cutoff_hz,
                          source=str(bag.path))


def _stats(x: np.ndarray) -> dict:
    x = x[np.isfinite(x)]
    return {"mean": float(np.mean(x)), "std": float(np.std(x)), "max_abs": float(np.max(np.abs(x)))}


def estimate_bag(bag, description=None, options=None, *, effects=(), out=None,
                 cutoff_hz: float | None = None, overwrite: bool = False) -> dict:
    """``cablelab estimate`` for a crane bag: swing-angle statistics (CONTRACT sec. 5) as JSON.

    Args:
        bag: bag path or an open :class:`~cablelab.bags.Bag`.
        description, options, effects: the estimate hook's arguments; the swing estimate is
            kinematic (no parameters, no model, no plant options), so it reads none of them.
        out: also write the per-sample estimates as ``/crane/swing_estimate`` (stamped like the
            motion capture) to this bag.
        cutoff_hz: optional low-pass of the angles before differentiation.
    """
    if not hasattr(bag, "pose"):
        from ...bags import open_bag

        bag = open_bag(bag)
    sw, rep = swing_from_bag(bag, cutoff_hz=cutoff_hz)
    res = {"plant": "crane", "samples": int(sw.t.shape[0]),
           "theta1": _stats(sw.theta1), "theta2": _stats(sw.theta2),
           "rope_length": _stats(sw.rope_length),
           "theta1_dot": _stats(sw.theta1_dot), "theta2_dot": _stats(sw.theta2_dot),
           "conditioning": rep.as_dict(), "problems": rep.problems()}
    if bag.has(SWING_TRUTH):
        tr = bag.joint_state(SWING_TRUTH, list(SWING_NAMES))
        ok = np.isfinite(tr.t)
        if ok.sum() >= 2:
            res["rms_error_vs_ground_truth"] = {
                n: float(np.sqrt(np.nanmean((getattr(sw, n) - np.interp(sw.t, tr.t[ok], tr.position[ok, i])) ** 2)))
                for i, n in enumerate(("theta1", "theta2", "rope_length"))}
    if out:
        write_swing_estimate(out, sw, bag.description_yaml, overwrite=overwrite)
        res["out"] = str(out)
    return res


def write_swing_estimate(path, sw: SwingAngles, description_yaml: str | None = None,
                         overwrite: bool = False) -> None:
    """Write ``/crane/swing_estimate`` (names theta1, theta2, rope_length; position + velocity)."""
    from ...bags import BagWriter

    with BagWriter(path, overwrite=overwrite) as w:
        if description_yaml:
            w.write_description(description_yaml)
        w.write_joint_states(SWING_ESTIMATE, sw.t, SWING_NAMES, position=sw.position,
                             velocity=sw.velocity)
