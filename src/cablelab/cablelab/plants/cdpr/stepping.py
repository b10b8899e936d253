"""When the CDPR simulator node steps and with which torques (ROS-free).

:class:`SimStepper` is the ``cable_sim_node``'s law over time: real time (``due``: the steps the
wall clock says are due, catching up at most 20 at once; the step a command answering the last
state drives computed as soon as that answer came, ``step_ahead``, so that its deadline only
publishes the state) or lock-step (a step as soon as the
command answering the last published state arrived, or after ``lockstep_timeout`` s wall without
one); without a fresh command the winch brakes hold (:class:`~.hardware.WinchBrakes` inside
:class:`~.hardware.SimulatedCdpr`); a scheduled mass change; the reference stamps published
around each state; and the counts /diagnostics reports. The node only moves messages.
"""
from __future__ import annotations

from typing import Callable

import numpy as np

from ...errors import CablelabError
from ...ros.inputs import WARN
from ...ros.status import add_problem
from .geometry import check_pulley_radius
from .hardware import SimulatedCdpr
from .sim import truth_from_parameters
from .trajectory import ReferenceTable, pick_and_place

__all__ = ["SimStepper", "MAX_CATCH_UP"]

MAX_CATCH_UP = 20       # steps run at once by a late real-time timer; more behind are dropped


#: the reference's default lead in real time (s): far enough ahead that a controller plans it in
#: blocks (off its state -> command path) instead of once per period
DEFAULT_LEAD = 0.05


def default_lead(rate: float) -> float:
    """The default lead of the published reference in real time: :data:`DEFAULT_LEAD` as a whole
    number of periods, at least two."""
    return max(2, round(DEFAULT_LEAD * rate)) / rate


class SimStepper:
    """The simulator node's per-step logic.

    Args:
        hardware: the simulated winches (settled on their brakes here: the robot is switched on
            hanging on its locked winch brakes, so the first state already carries the load).
        rate: Hz of the states (= command sampling).
        real_time: step on the wall clock (False: lock-step with the controller).
        lockstep_timeout: s wall a lock-step waits for the answering command.
        reference: the published reference (:class:`~.trajectory.ReferenceTable`).
        reference_lead: s the published reference runs ahead of the state (negative:
            :func:`default_lead` in real time, 0 in lock-step); None = no reference published.
        duration: sim time after which :attr:`done` (0 = never).
        mass_change, mass_change_time: kg put on the platform at that sim time (negative: never);
            ``on_mass_change(kg)`` is called after it happened.
    """

    def __init__(self, hardware: SimulatedCdpr, rate: float, real_time: bool, lockstep_timeout: float,
                 reference: ReferenceTable, reference_lead: float | None = -1.0, duration: float = 0.0,
                 mass_change: float = 0.0, mass_change_time: float = -1.0,
                 on_mass_change: Callable[[float], None] | None = None):
        self.hw, self.sim = hardware, hardware.sim
        self.rate, self.real_time, self.lockstep_timeout = rate, real_time, lockstep_timeout
        self.reference = reference
        self.publish_reference = reference_lead is not None
        lead = -1.0 if reference_lead is None else reference_lead
        # real time: the reference two steps ahead goes out right after the state (off the
        # state -> command critical path; the consumers look it up by stamp, and a controller
        # prepares the reference terms of the next stamp while the plant steps)
        self.reference_lead = (default_lead(rate) if real_time else 0.0) if lead < 0 else lead
        self._ref_started = False
        self.duration = duration
        self.mass_change, self.mass_change_time = mass_change, mass_change_time
        self.on_mass_change = on_mass_change
        self.u = None               # the last good command
        self.u_stamp = None         # stamp of the state it answers, if it says
        self.commands = 0           # good commands received
        self.commands_at_pub = 0    # ... when the last state was published (lock-step)
        self.fallbacks = 0
        self.fallbacks_running = 0  # ... after the first command (not the start-up wait)
        self.slack_steps = 0
        # real-time misses (what bench/bench_realtime.py sums as missed cycles): steps run one or
        # more periods after they were due, steps dropped when too far behind, and steps that had
        # to apply a command answering an older state (the controller did not answer in time)
        self.late_steps = 0
        self.dropped_steps = 0
        self.stale_command_steps = 0
        self.missed_steps = 0       # steps with any of: late, braked, stale command (each once)
        self.command_age = [0, 0, 0]   # steps whose command answers the state 1, 2, >= 3 periods back
        self.k = 0                  # steps computed
        self.ahead = False          # the last step was computed ahead of its deadline (step_ahead)
        self.done = False
        self.last_publish = 0.0     # wall time of the last published state
        self._wall0 = None          # wall time of sim time 0 (real time)
        hardware.start()

    @classmethod
    def from_parameters(cls, description, v, who: str = "cable_sim_node",
                        on_mass_change: Callable[[float], None] | None = None) -> "SimStepper":
        """The simulator node's stepper: the MuJoCo CAROCA of ``description`` with the truth of
        the validated node parameters ``v`` (:data:`~.nodes.parameters.SIM`), at rest at the
        start of the pick-and-place (point A) at ``v.rate`` Hz, publishing that s-curve unless
        ``v.publish_reference`` is false.

        Raises:
            CablelabError: one line naming ``who``: no cdpr section, a parameter the specs alone
                cannot check (:func:`~.sim.truth_from_parameters`), or a pulley radius that does
                not fit the geometry at A (:func:`~.geometry.check_pulley_radius`).
        """
        c = description.cdpr
        if c is None:
            raise CablelabError(f"{who} --plant cdpr: the description has no cdpr section")
        truth = truth_from_parameters(who, v, len(c.cables), v.rate)
        start = pick_and_place(np.array([0.0])).position[0]
        check_pulley_radius(c.exit_points, c.anchor_points, start[None], None, c.pulley_radius,
                            c.swivel_axes, f"{who}: description cdpr.pulley_radius")
        return cls(SimulatedCdpr(description, truth, v.rate, start), v.rate, v.real_time, v.lockstep_timeout,
                   ReferenceTable(v.rate, v.settle, v.trajectory_speed),
                   v.reference_lead if v.publish_reference else None, v.duration, v.mass_change,
                   v.mass_change_time, on_mass_change)

    def command(self, values, stamp: float | None) -> None:
        """A good command (n,) N m, naming the stamp of the state it answers (or None)."""
        self.u = values.copy()
        self.commands += 1
        self.u_stamp = stamp

    def due(self, now: float) -> int:
        """Real time: the steps due at wall time ``now`` (the first on time, the rest late; at most
        :data:`MAX_CATCH_UP`, those further behind dropped and counted)."""
        published = self.k - self.ahead     # a step computed ahead is due at its deadline
        if self._wall0 is None:
            self._wall0 = now - published / self.rate
        due = int((now - self._wall0) * self.rate) - published
        if self.commands and due > 1:
            self.late_steps += min(due, MAX_CATCH_UP) - 1   # ran at least one period after they were due
        if due > MAX_CATCH_UP - 1:                          # far behind: do not try to catch up forever
            if self.commands:
                self.dropped_steps += due - MAX_CATCH_UP
            self._wall0 = now - published / self.rate
            due = MAX_CATCH_UP
        return max(0, due)

    def time_left(self, now: float) -> float:
        """Real time: s of wall time from ``now`` to the deadline of the next state to publish
        (inf before the first :meth:`due`)."""
        if self._wall0 is None:
            return float("inf")
        return self._wall0 + (self.k - self.ahead + 1) / self.rate - now

    def step_ahead(self, now: float) -> bool:
        """Real time: when the last command answers the last published state, the step it drives
        (the same step the deadline would run: the answer applied from that state's sim time on)
        is computed now, as soon as the answer came; its state is published at its deadline
        (:meth:`due` counts it there as the first step due, :attr:`ahead` until then). The
        deadline then only publishes. False (nothing done) when the last command answers
        another state (or does not say which), or a step is already ahead, or :attr:`done`."""
        if not self.real_time or self.ahead or self.done or self.u_stamp is None \
                or abs(self.u_stamp - self.sim.time) >= 0.5 / self.rate:
            return False
        self.step(now, fresh=True)
        self.ahead = True
        return True

    def steps_due(self, now: float) -> int:
        """The steps the node's timer runs at wall time ``now``: :meth:`due` in real time, one in
        lock-step (:meth:`step` says whether it went)."""
        return self.due(now) if self.real_time else 1

    def step(self, now: float, fresh: bool = False, late: bool = False) -> bool:
        """One step at wall time ``now``; False when lock-step still waits for the answer.
        ``fresh``: real time, the last command is not older than the command timeout."""
        missed = late
        if not self.real_time:
            if self.u_stamp is not None:      # the controller says which state it answers
                answered = abs(self.u_stamp - self.sim.time) < 1e-6
            else:
                answered = self.commands > self.commands_at_pub
            if not answered and now - self.last_publish < self.lockstep_timeout:
                return False                            # lock-step: wait for the controller
            fresh = answered and self.u is not None     # an answer is fresh however late it came
        else:
            fresh = fresh and self.u is not None
        if not fresh:
            self.hw.command = self.u          # the brakes hold the last command received
            self.hw.write(None)
            self.fallbacks += 1
            if self.commands:
                self.fallbacks_running += 1
                missed = True
        else:
            if self.real_time and self.u_stamp is not None:
                age = int(round((self.sim.time - self.u_stamp) * self.rate))   # 0: the last state
                self.command_age[min(max(age, 0), 2)] += 1
                if age > 0:
                    self.stale_command_steps += 1       # the answer to the last state is not here
                    missed = True
            self.hw.write(self.u)
        self.k += 1
        if self.mass_change and 0 <= self.mass_change_time <= self.sim.time:
            self.put_on_mass()
        if missed and self.commands and self.real_time:
            self.missed_steps += 1
        if self.sim.slack().any():
            self.slack_steps += 1
        if self.duration and self.sim.time >= self.duration:
            self.done = True
        return True

    def put_on_mass(self, model: bool = True) -> None:
        """The scheduled payload goes on now: the simulation gains it (``model`` False: only its
        truth, the compiled path changed the model), then ``on_mass_change(kg)``."""
        kg, self.mass_change = self.mass_change, 0.0
        self.sim.add_mass(kg, model=model)
        if self.on_mass_change is not None:
            self.on_mass_change(kg)

    def published(self, now: float) -> None:
        """The state of the present sim time went out at wall time ``now``."""
        self.last_publish = now
        self.commands_at_pub = self.commands
        self.ahead = False

    def reference_stamps(self, t: float) -> tuple[list[float], list[float]]:
        """Stamps of the reference samples to publish (before, after) the state of stamp ``t``:
        the state's own before it without a lead; with one, at the start every stamp up to the
        lead before it, then ``t + lead`` after each state (it waits for the next state)."""
        if not self.publish_reference:
            return [], []
        lead = self.reference_lead
        if not lead:
            return [t], []
        before = [] if self._ref_started else [t + i / self.rate for i in range(int(round(lead * self.rate)))]
        self._ref_started = True
        return before, [t + lead]

    def values(self) -> dict:
        """The counts for /diagnostics."""
        return {"sim time s": f"{self.sim.time:.3f}", "brake (fallback) steps": str(self.fallbacks),
                "brake steps after the first command": str(self.fallbacks_running),
                "slack cable steps": str(self.slack_steps),
                "mode": "real time" if self.real_time else "as fast as possible (lock-step)",
                "late steps": str(self.late_steps), "dropped steps": str(self.dropped_steps),
                "stale command steps": str(self.stale_command_steps),
                "missed steps": str(self.missed_steps),
                "command age 1/2/3+ periods": "/".join(str(a) for a in self.command_age)}

    def report(self, level: int, msg: str, values: dict) -> tuple[int, str, dict]:
        """The simulator's part of /diagnostics: ``values`` gains the counts (:meth:`values`);
        ``(level, msg)`` a WARN naming the cables slack now (1-based)."""
        values.update(self.values())
        slack = [str(i + 1) for i in np.flatnonzero(self.sim.truth_state()["slack"])]
        if slack:
            level, msg = add_problem(level, msg, WARN, "slack cable(s) " + ", ".join(slack))
        return level, msg, values
