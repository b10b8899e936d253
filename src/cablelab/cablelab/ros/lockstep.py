"""Lock-step between a simulator node and the controller that answers its states.

A simulator in lock-step publishes the state of sim time t, then advances one period only after
the command answering that state arrived: CPU load or DDS latency then slows the run down
instead of delaying the control loop (a delayed command would destabilise stiff loops, e.g. the
LiCAS arm joints, k_d / I ~ 1000 1/s, tolerate < 1 ms).

Matching: a command that names the stamp of the state it answers
(:func:`cablelab.ros.convert.command_msg`, as the cablelab controllers send) is applied only if
it answers the latest state; an answer to an earlier one (e.g. to a state resent while waiting,
or published while the simulation still ran in real time) is counted and ignored, so it can
never add a control delay. A command naming no stamp answers the last published state.

Two ways to start (the simulator node chooses):

* ``wait_first=True``: time does not start before the first answer; meanwhile the state is
  resent every ``resend`` s (the controller may not be connected yet). Axis, suspended.
* ``wait_first=False``: real time (the simulator's own no-command fallback) until commands flow,
  then lock-step. Crane.

Either way, without an answer for ``timeout`` s (after the first command) the simulator drops
back to real time until commands flow again (``timeout=inf``: it waits for ever).

The node calls :meth:`LockStep.published` after every state it publishes, :meth:`LockStep.offer`
with the stamp of every valid command (apply the command only if it returns True), and
:meth:`LockStep.poll` on every timer tick, which says what to do.
"""
from __future__ import annotations

import math
import time

from .convert import same_stamp

__all__ = ["LockStep", "ADVANCE", "FREE", "WAIT", "RESEND"]

ADVANCE = "advance"   # the answer to the last state is here: advance with it
FREE = "free"         # no lock-step now: the simulator's real-time rules apply
WAIT = "wait"         # wait for the answer (do nothing this tick)
RESEND = "resend"     # wait, and publish the last state again


class LockStep:
    """Lock-step state of one simulator node (see the module docstring).

    Args:
        enabled: lock-step on (False: :meth:`poll` always says FREE, :meth:`offer` accepts all)
        wait_first: wait for the first answer before time starts (else real time until
            commands flow)
        timeout: s wall without an answer after which the simulator falls back to real time
            (inf: wait for ever)
        resend: s wall between resends of the waited-for state (0: never resend)
    """

    def __init__(self, enabled: bool, *, wait_first: bool = True, timeout: float = math.inf,
                 resend: float = 0.0):
        self.enabled = bool(enabled)
        self.wait_first = bool(wait_first)
        self.timeout = float(timeout)
        self.resend = float(resend)
        self.answered = False          # the command answering the last published state arrived
        self.flowing = False           # commands flow (lock-step engaged when not wait_first)
        self.started = False           # a command arrived once (wait_first: time started)
        self.stale_answers = 0         # answers to earlier states, ignored
        self.t_state: float | None = None
        self.published_at = time.monotonic()

    def published(self, t: float, now: float | None = None) -> None:
        """The simulator has just published (or resent) the state of sim time ``t`` (s)."""
        self.answered = False
        self.t_state = float(t)
        self.published_at = time.monotonic() if now is None else now

    def offer(self, stamp: float | None) -> bool:
        """A valid command arrived that answers the state of ``stamp`` (None: does not say).
        True: apply it; False: it answers an earlier state (counted, ignore it)."""
        if not self.enabled:
            return True
        self.flowing = self.started = True
        if stamp is not None and not same_stamp(stamp, self.t_state):
            self.stale_answers += 1
            return False
        self.answered = True
        return True

    def poll(self, now: float | None = None) -> str:
        """What the simulator does on this tick: ADVANCE, WAIT, RESEND or FREE."""
        if not self.enabled:
            return FREE
        if self.answered:
            return ADVANCE
        now = time.monotonic() if now is None else now
        waited = now - self.published_at
        if not self.flowing:
            if not self.wait_first or self.started:
                return FREE            # real time until commands flow (again)
        elif waited >= self.timeout:
            self.flowing = False       # no answer for `timeout` s: real time until commands flow
            return FREE
        return RESEND if self.resend > 0 and waited > self.resend else WAIT
