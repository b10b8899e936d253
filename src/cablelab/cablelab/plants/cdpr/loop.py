"""The CDPR's law in a control loop (:mod:`cablelab.control_loop`), ROS-free.

:class:`ReferenceLaw` is the ``pd_feedforward`` node's law, :class:`~.live.LiveController`
(PD on the motor angles about the inverse geometric model of the reference + the feedforward of
001 eq. 14 with the live mass estimate + friction compensation), fed by a reference known in the
loop's process (e.g. :class:`~.trajectory.ReferenceTable`) instead of a topic. As in the node,
the reference terms of the next period (IGM, desired rates, feedforward tensions) are prepared
after the write (:meth:`ReferenceLaw.prepare_next`), so that the deadline path only adds the PD
part; an estimate that arrives (:meth:`ReferenceLaw.estimate`) invalidates what was prepared
with the previous mass.

When the reference is a table on the loop's grid (``rows``, e.g.
:meth:`~.trajectory.ReferenceTable.rows`), the terms that depend on the reference only (IGM,
rates, friction compensation, the right inverse of W) are computed for ``block`` periods at once
(:meth:`~.live.LiveController.plan`, vectorised) and each period finishes the command with the
live estimate and the motor state in a few operations on (n,) arrays
(:meth:`~.live.LiveController.planned_law`): the same law to round-off, at a fraction of the
per-period CPU.
"""
from __future__ import annotations

from typing import Callable

import numpy as np

from ...hardware import HardwareState
from .live import LiveController, ReferencePlan, ReferenceTerms

__all__ = ["ReferenceLaw"]

IDENTITY = np.array([1.0, 0.0, 0.0, 0.0])


class ReferenceLaw:
    """:class:`~.live.LiveController` driven by ``reference(t) -> (position, velocity,
    acceleration)`` (platform level: orientation identity), a :class:`~cablelab.control_loop.ControlLaw`.

    Args:
        controller: the live controller (its config: gains, PD/PDFF, nominal mass, ...).
        reference: the desired platform motion at a stamp, m, m/s, m/s^2.
        rows: optional ``rows(k0, count) -> (stamps, positions, velocities, accelerations)`` of
            the same reference on the grid ``k / rate`` (module docstring); None: every period
            prepares its terms alone.
        rate: Hz of that grid (the loop's rate).
        block: periods planned at once.
    """

    def __init__(self, controller: LiveController, reference: Callable[[float], tuple],
                 rows: Callable[[int, int], tuple] | None = None, rate: float | None = None, block: int = 64):
        if rows is not None and not (rate and rate > 0):
            raise ValueError(f"ReferenceLaw: a reference grid needs its rate > 0 Hz, got {rate}")
        self.controller = controller
        self.reference = reference
        self.rows, self.rate, self.block = rows, rate, max(1, int(block))
        self.plan: ReferencePlan | None = None
        self._k0 = 0                    # grid index of the plan's first row
        self.prepared: ReferenceTerms | None = None
        self.prepared_used = 0          # commands whose reference terms were prepared ahead

    @property
    def status(self) -> list:
        return self.controller.status

    def estimate(self, t: float, mass: float, com=None) -> bool:
        """A live estimate of stamp ``t`` (kg, (x_G, y_G) m); False if rejected as implausible."""
        ok = self.controller.estimate(t, mass, com)
        if ok:
            self.prepared = None        # prepared with the previous mass
        return ok

    def terms(self, t: float) -> ReferenceTerms | None:
        """The reference terms of stamp ``t`` (:meth:`LiveController.prepare`)."""
        pos, vel, acc = self.reference(t)
        return self.controller.prepare(t, pos, IDENTITY, vel, acc)

    def _row(self, t: float) -> int:
        """Row of the plan for stamp ``t``, or -1 when the plan does not hold it."""
        plan = self.plan
        if plan is None:
            return -1
        i = int(t * self.rate + 0.5) - self._k0
        return i if 0 <= i < len(plan.t) and abs(plan.t[i] - t) <= 1e-9 else -1

    def prepare_next(self, t: float, spare: bool = True) -> None:
        """Prepare the reference terms of stamp ``t`` (the next period), off the deadline path.
        With a grid: plan the ``block`` periods from ``t`` when the plan has less than a
        sixteenth of a block left and there is time to ``spare``; without time to spare (the loop is
        catching up), only the terms of ``t`` alone when the plan does not hold it (cheaper than
        a block)."""
        if self.rows is None:
            self.prepared = self.terms(t)
            return
        i = self._row(t)
        if spare and (i < 0 or len(self.plan) - i < max(1, self.block // 16)):
            k0 = int(t * self.rate + 0.5)
            stamps, pos, vel, acc = self.rows(k0, self.block)
            self.plan, self._k0 = self.controller.plan(stamps, pos, vel, acc), k0
        elif i < 0:
            self.prepared = self.terms(t)

    def update(self, state: HardwareState) -> np.ndarray | None:
        if self.rows is not None:
            i = self._row(state.t)
            if i >= 0:
                self.prepared_used += 1
                return self.controller.planned_law(self.plan, i, state.position, state.velocity)
        ref = self.prepared
        if ref is not None and abs(ref.t - state.t) <= 1e-9:
            self.prepared_used += 1
        else:
            ref = self.terms(state.t)
        self.prepared = None
        return None if ref is None else self.controller.law(ref, state.position, state.velocity)
