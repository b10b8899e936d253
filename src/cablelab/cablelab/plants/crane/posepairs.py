"""Motion-capture pose pairs matched with the slew angle of their stamp (ROS-free).

The swing estimator gets the boom-tip and payload poses (same stamps) and the slew angle from the
joint states on separate topics, which DDS does not order between them. :class:`PosePairs` pairs
each payload pose with the tip pose of its stamp, keeps the pairs until the slew angle of their
stamp is known (interpolated over the unwrapped angles received), and hands them out in stamp
order; a pair that waited more than ``max_wait`` s of stamps takes the latest angle (counted).
:class:`PairedSwing` runs the pairs through the swing tracker: the live estimator's core.
"""
from __future__ import annotations

from collections import deque

import numpy as np

from .swing import SwingTracker

__all__ = ["PosePairs", "PairedSwing"]


class PosePairs:
    """Pose pairs waiting for their slew angle.

    Args:
        max_wait: s (of stamps) a pair waits for the slew angle of its stamp.
    """

    def __init__(self, max_wait: float):
        self.max_wait = max_wait
        self.slews = deque(maxlen=400)      # (stamp, slew angle) of the joint states
        self.pending = deque(maxlen=100)    # (stamp, tip, payload) waiting for the slew angle
        self.tip = None                     # (stamp, position) of the last tip pose
        self.unpaired = 0                   # payload poses without the tip pose of their stamp
        self.unsynced = 0                   # pairs that used the latest slew angle instead

    def slew(self, t: float, angle: float) -> None:
        """A slew angle (rad) of stamp ``t`` (not finite or older than the newest: ignored)."""
        if np.isfinite(t) and (not self.slews or t > self.slews[-1][0]):
            self.slews.append((t, float(angle)))

    def tip_pose(self, t: float, position) -> None:
        self.tip = (t, position)

    def payload_pose(self, t: float, position) -> None:
        """A payload pose: paired with the tip pose of the same stamp, else counted unpaired."""
        if self.tip is None or abs(self.tip[0] - t) > 1e-6:
            self.unpaired += 1
            return
        self.pending.append((t, self.tip[1], position))

    def slew_at(self, t: float) -> float | None:
        """Slew angle at stamp t (interpolated in the buffer; None if not yet received)."""
        if not self.slews or self.slews[-1][0] < t - 1e-9:
            return None
        ts = np.array([s[0] for s in self.slews])
        vs = np.unwrap(np.array([s[1] for s in self.slews]))
        return float(np.interp(t, ts, vs))

    def ready(self):
        """Yield ``(t, tip, payload, slew)`` of every pending pair whose slew angle is known, in
        stamp order (or that waited longer than ``max_wait``: the latest angle)."""
        while self.pending:
            t, tip, pay = self.pending[0]
            slew = self.slew_at(t)
            if slew is None:
                if self.pending[-1][0] - t < self.max_wait or not self.slews:
                    return
                slew = self.slews[-1][1]
                self.unsynced += 1
            self.pending.popleft()
            yield t, tip, pay, slew


class PairedSwing:
    """The live swing estimate (what ``payload_estimator --plant crane`` runs): each pose pair of
    :attr:`pairs` with the slew angle of its stamp goes through :attr:`tracker`
    (:class:`.swing.SwingTracker`).

    Args:
        max_wait: s (of stamps) a pair waits for the slew angle of its stamp.
        velocity_tau: time constant smoothing the swing rates, s.
    """

    def __init__(self, max_wait: float, velocity_tau: float):
        self.pairs = PosePairs(max_wait)
        self.tracker = SwingTracker(tau=velocity_tau)

    def estimates(self):
        """Yield ``(t, [theta1, theta2, rope length], their rates)`` of every pair whose slew
        angle is known, in stamp order (dropouts and frozen stamps are counted instead)."""
        for t, tip, pay, slew in self.pairs.ready():
            _status, x, v = self.tracker.update(t, tip, pay, slew)
            if x is not None:
                yield t, x, v

    def report(self) -> tuple[str, dict]:
        """``(problem, values)`` for /diagnostics: the counts by sample status and of unpaired
        and unsynchronised poses; the problem names the dropouts, frozen stamps and irregular
        periods (empty without any)."""
        c = self.tracker.counts
        values = {f"samples {k}": str(v) for k, v in c.items()}
        values["unpaired poses"] = str(self.pairs.unpaired)
        values["poses without a synchronous slew angle"] = str(self.pairs.unsynced)
        problem = ""
        if c["dropout"] or c["frozen"] or c["irregular"]:
            problem = (f"{c['dropout']} motion-capture dropouts, {c['frozen']} frozen stamps, "
                       f"{c['irregular']} irregular periods")
        return problem, values
