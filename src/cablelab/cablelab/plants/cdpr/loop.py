"""The CDPR's law in a control loop (:mod:`cablelab.control_loop`), ROS-free.

:class:`ReferenceLaw` is the ``pd_feedforward`` node's law, :class:`~.live.LiveController`
(PD on the motor angles about the inverse geometric model of the reference + the feedforward of
001 eq. 14 with the live mass estimate + friction compensation), fed by a reference known in the
loop's process (e.g. :class:`~.trajectory.ReferenceTable`) instead of a topic. As in the node,
the reference terms of the next period (IGM, desired rates, feedforward tensions) are prepared
after the write (:meth:`ReferenceLaw.prepare_next`), so that the deadline path only adds the PD
part; an estimate that arrives (:meth:`ReferenceLaw.estimate`) invalidates what was prepared
with the previous mass.
"""
from __future__ import annotations

from typing import Callable

import numpy as np

from ...hardware import HardwareState
from .live import LiveController, ReferenceTerms

__all__ = ["ReferenceLaw"]

IDENTITY = np.array([1.0, 0.0, 0.0, 0.0])


class ReferenceLaw:
    """:class:`~.live.LiveController` driven by ``reference(t) -> (position, velocity,
    acceleration)`` (platform level: orientation identity), a :class:`~cablelab.control_loop.ControlLaw`.

    Args:
        controller: the live controller (its config: gains, PD/PDFF, nominal mass, ...).
        reference: the desired platform motion at a stamp, m, m/s, m/s^2.
    """

    def __init__(self, controller: LiveController, reference: Callable[[float], tuple]):
        self.controller = controller
        self.reference = reference
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

    def prepare_next(self, t: float) -> None:
        """Prepare the reference terms of stamp ``t`` (the next period), off the deadline path."""
        self.prepared = self.terms(t)

    def update(self, state: HardwareState) -> np.ndarray | None:
        ref = self.prepared
        if ref is not None and abs(ref.t - state.t) <= 1e-9:
            self.prepared_used += 1
        else:
            ref = self.terms(state.t)
        self.prepared = None
        return None if ref is None else self.controller.law(ref, state.position, state.velocity)
