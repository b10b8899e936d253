"""The live nodes' samples (ROS-free): the check of a joint state against the model's joints
(:func:`joint_values`) and the payload estimator's sliding window (:class:`PayloadWindow`): joint
states and measured tendon tensions kept by stamp, paired, and fitted every few samples.

DDS orders samples within a topic, not across topics: the tension sample of a stamp may arrive
before or after the joint state of that stamp. Both streams are kept over the window and, at a
fit, the tensions are interpolated onto the joint-state stamps they cover (as the bag path of
:func:`.dataset.dataset` does); a joint state outside the tensions' span waits for them.
"""
from __future__ import annotations

from collections import deque

import numpy as np

from ...errors import CablelabError
from ...ros.status import SkipLog
from ...timebase import interp_columns
from .estimation import PayloadEstimate, payload_estimate
from .mjcf import actuated_joints, dof_joints

__all__ = ["PayloadWindow", "joint_values"]

#: fewest paired samples (and share of the window they must span) before a fit
MIN_SAMPLES, MIN_SPAN = 60, 0.5


def joint_values(names, joints, *arrays) -> np.ndarray | None:
    """The ``arrays`` of a joint message concatenated when its ``names`` are the model's
    ``joints`` in order and each array has one value per joint (what an input monitor then checks
    for finite values), else None."""
    n = len(joints)
    if list(names or ()) != list(joints) or any(a is None or np.size(a) != n for a in arrays):
        return None
    return np.concatenate([np.asarray(a, float).ravel() for a in arrays])


class PayloadWindow:
    """Payload fits of the last ``window`` s of one machine.

    Args:
        description: a description with an ``mjcf`` section naming ``payload_body``.
        window: s of stamps fitted; every: fit every this many accepted joint states.
    """

    def __init__(self, description, window: float, every: int):
        sec = description.mjcf
        if sec is None or not sec.payload_body:
            raise CablelabError("payload estimate: the description names no mjcf.payload_body")
        model = sec.compiled()
        self.description, self.window, self.every = description, float(window), int(every)
        self.joints = dof_joints(model)
        self.tendons = list(sec.tendons or ())
        measured = set(sec.joints) if sec.joints is not None else set(actuated_joints(model))
        self.driven = np.array([j in measured for j in self.joints])
        self.states: deque = deque()       # (t, q, effort of the driven joints, 0 elsewhere)
        self.tensions: deque = deque()     # (t, tensions of sec.tendons)
        self.count = 0
        self.last: PayloadEstimate | None = None
        self.last_t = float("nan")
        self.skips = SkipLog()

    def state(self, t: float, q, effort) -> PayloadEstimate | None:
        """A joint state (dof order): the new estimate when one is due, else None. A stamp not
        newer than the last one is skipped."""
        if self.states and not t > self.states[-1][0]:
            self.skips.skip(f"joint state stamp {t:.6f} s not after the last one")
            return None
        self.states.append((float(t), np.array(q, float), np.where(self.driven, effort, 0.0)))
        self._trim(self.states)
        self.count += 1
        return self.fit() if self.count % self.every == 0 else None

    def state_values(self, names, q, effort) -> np.ndarray | None:
        """A joint-state message's positions and efforts (dof order) concatenated, the effort of an
        undriven joint (not measured) taken as zero, when its ``names`` are the model's joints
        with one value each (:func:`joint_values`), else None."""
        if effort is not None and np.size(effort) == self.driven.size:
            effort = np.where(self.driven, effort, 0.0)
        return joint_values(names, self.joints, q, effort)

    def report(self, level: int, msg: str, values: dict) -> tuple[int, str, dict]:
        """The estimator's part of /diagnostics: ``values`` gains the samples in the window and
        the last fitted mass; ``(level, msg)`` a WARN for a recently skipped sample or fit."""
        values["samples in window"] = str(len(self.states))
        if self.last is not None:
            values["payload mass kg"] = f"{self.last.m:.6g}"
        level, msg = self.skips.warn(level, msg)
        return level, msg, values

    def tension_values(self, names, values) -> np.ndarray | None:
        """The tensions of the section's ``tendons`` in a message naming them (any order, others
        ignored; names and values of equal number), else None."""
        names = list(names or ())
        if values is None or len(names) != np.size(values) or not set(self.tendons) <= set(names):
            return None
        return np.array([np.asarray(values, float).ravel()[names.index(x)] for x in self.tendons])

    def tension(self, t: float, values) -> None:
        """A tension sample of the section's ``tendons`` (N, in that order)."""
        if self.tensions and not t > self.tensions[-1][0]:
            self.skips.skip(f"tension stamp {t:.6f} s not after the last one")
            return
        self.tensions.append((float(t), np.array(values, float)))
        self._trim(self.tensions)

    def _trim(self, buf: deque) -> None:
        newest = max(self.states[-1][0] if self.states else -np.inf,
                     self.tensions[-1][0] if self.tensions else -np.inf)
        while buf and newest - buf[0][0] > self.window:
            buf.popleft()

    def paired(self):
        """``(t, q, effort, tension)`` of the joint states in the window that have tensions at
        their stamp (tension None for a machine without measured tendons)."""
        if not self.states:
            return np.zeros(0), np.zeros((0, len(self.joints))), np.zeros((0, len(self.joints))), None
        t = np.array([s[0] for s in self.states])
        q = np.array([s[1] for s in self.states])
        eff = np.array([s[2] for s in self.states])
        if not self.tendons:
            return t, q, eff, None
        if not self.tensions:
            return t[:0], q[:0], eff[:0], np.zeros((0, len(self.tendons)))
        tt = np.array([s[0] for s in self.tensions])
        tv = np.array([s[1] for s in self.tensions])
        keep = (t >= tt[0] - 1e-9) & (t <= tt[-1] + 1e-9)
        ten = interp_columns(t[keep], tt, tv)
        return t[keep], q[keep], eff[keep], ten

    def fit(self) -> PayloadEstimate | None:
        """The payload fitted to the paired window, or None (too few samples, or the fit failed:
        the reason is in :attr:`skips`)."""
        t, q, eff, ten = self.paired()
        if len(t) < MIN_SAMPLES or t[-1] - t[0] < MIN_SPAN * self.window:
            return None
        try:
            est = payload_estimate(t, q, eff, self.description, tension=ten, driven=self.driven)
        except CablelabError as exc:
            self.skips.skip(" ".join(str(exc).split()))
            return None
        self.skips.last_problem = ""
        self.last, self.last_t = est, float(t[-1])
        return est
