"""The CDPR estimator's and controller's samples across topics (ROS-free).

DDS orders samples within a topic, not across topics: a tension sample or a motor state must meet
the pose or reference of its own stamp, which may come before or after it. :class:`EstimateStream`
(the ``payload_estimator``) and :class:`CommandStream` (the ``pd_feedforward`` controller) keep
the samples by stamp, decide when a sample is estimated or commanded, and count what was skipped
and why; the per-sample laws are :class:`~.live.LiveEstimator` and :class:`~.live.LiveController`.
The nodes only decode, check (:class:`cablelab.ros.inputs.InputMonitor`) and publish.
"""
from __future__ import annotations

import numpy as np

from ...ros.inputs import ERROR, WARN
from ...ros.status import SkipLog, add_problem
from ...stamped import StampedBuffer
from .control import PdffConfig
from .live import ControllerConfig, EstimatorConfig, LiveController, LiveEstimator

__all__ = ["EstimateStream", "CommandStream", "controller_config", "estimator_config"]


def estimator_config(v) -> EstimatorConfig:
    """The live estimator's options from validated node parameters ``v`` (``model``,
    ``tensions``, ``pose``, ``platform_inertia``, ``coulomb``, ``viscous``, ``stale_after``,
    ``pulley_radius`` (0: the description's))."""
    return EstimatorConfig(model=v.model, tensions=v.tensions, pose=v.pose, platform_inertia=v.platform_inertia,
                           coulomb=v.coulomb, viscous=v.viscous, stale_after=v.stale_after,
                           pulley_radius=v.pulley_radius if v.pulley_radius > 0 else None)


def controller_config(v, platform_mass: float) -> ControllerConfig:
    """The live controller's options from validated node parameters ``v`` (``feedforward``,
    ``nominal_mass`` (0: ``platform_mass``, else 366 kg), ``kp``, ``kd``, ``coulomb``, ``viscous``,
    ``min_tension``, ``preload``, ``max_torque``, ``model``, ``estimate_timeout``)."""
    gains = PdffConfig(kp=v.kp, kd=v.kd, coulomb=v.coulomb, viscous=v.viscous,
                       min_tension=v.min_tension, preload=v.preload, max_torque=v.max_torque)
    return ControllerConfig(feedforward=v.feedforward, nominal_mass=v.nominal_mass or platform_mass or 366.0,
                            estimate_timeout=v.estimate_timeout, gains=gains, model=v.model)


class EstimateStream:
    """Payload estimates of tension (or motor) samples at the pose of their stamp.

    Args:
        config: the estimator's options.
        batch: estimate only the newest sample of a period (:meth:`poll`), not each one.
    """

    def __init__(self, config: EstimatorConfig, batch: bool = False):
        self.config, self.batch = config, batch
        self.estimator: LiveEstimator | None = None
        self.poses = StampedBuffer()    # t -> (position, quat wxyz, acceleration); may run ahead
        self.motor = None               # (t, velocity, effort)
        self.skips = SkipLog()
        self.batch_newest = None        # (t, tensions) of the newest input sample of the period (batch)

    def describe(self, cdpr, gravity: float) -> None:
        """The plant's cdpr section (None: the description has none) configures the estimator."""
        if cdpr is None:
            self.skips.last_problem = "plant description has no cdpr section"
            return
        self.estimator = LiveEstimator(cdpr, gravity, self.config)

    def pose(self, t: float, position, quat_wxyz, acceleration=None) -> None:
        self.poses.push(t, (position, quat_wxyz, acceleration))

    def sample(self, t: float, tensions=None, motor=None):
        """A tension sample (``tensions`` (n,) N, or ``motor`` = (velocity, effort) of the winches):
        ``(t, mass, com)`` to publish now, or None (skipped, or kept for :meth:`poll` in batch)."""
        if motor is not None:
            self.motor = (t, *motor)
        if self.batch:
            self.batch_newest = (t, tensions)
            return None
        return self.estimate(t, tensions)

    def poll(self):
        """Batch: the estimate of the newest sample of the period, or None."""
        if self.batch_newest is None:
            return None
        (t, tensions), self.batch_newest = self.batch_newest, None
        return self.estimate(t, tensions)

    def estimate(self, t: float, tensions):
        """``(t, mass, com)``, or None when a check failed (:attr:`skips` says why)."""
        if self.estimator is None:
            return self.skips.skip("waiting for /plant_description")
        if not self.poses:
            return self.skips.skip(f"no {self.config.pose} pose yet")
        tp, (pos, quat, acc) = self.poses.at(t)
        kw = {"tensions": tensions}
        if self.config.tensions == "motor":
            _, qd, eff = self.motor
            kw = {"effort": eff, "motor_velocity": qd}
        res = self.estimator.update(t, position=pos, quat=quat, acceleration=acc, input_times={"pose": tp}, **kw)
        if res is None:
            return self.skips.skip(self.estimator.status[-1][1])
        return (t, *res)

    def report(self, level: int, msg: str, values: dict) -> tuple[int, str, dict]:
        """The estimator's part of /diagnostics: ``(level, msg)`` raised to the worst problem of
        the estimator (ERROR while no description configured it), else a WARN for recently
        skipped samples when nothing else is wrong; ``values`` gains the counts and options."""
        est_status = self.estimator.status if self.estimator is not None else [(ERROR, self.skips.last_problem)]
        worst = max((s[0] for s in est_status), default=0)
        if worst > 0:
            level, msg = add_problem(level, msg, worst, est_status[-1][1])
        elif self.skips.is_recent() and level == 0:
            level, msg = WARN, f"skipped samples ({self.skips.last_problem})"
        values.update({"skipped": str(self.skips.skipped), "last problem": self.skips.last_problem or "none",
                       "model": self.config.model, "tensions": self.config.tensions, "pose": self.config.pose})
        return level, msg, values


class CommandStream:
    """Commands of motor states at the reference (and, awaited, the estimate) of their stamp.

    The reference of the next stamp is prepared (:meth:`prepare_next`) after a command, off the
    state -> command path; a new estimate prepares it again at once with the new mass.

    Args:
        feedforward: PDFF (False: PD).
        sync_wait: s wall a state waits for the reference of its stamp before the latest is used.
        estimate_wait: s wall a state waits for the estimate of its stamp (0 = never).
    """

    def __init__(self, feedforward: bool, sync_wait: float, estimate_wait: float):
        self.sync_wait, self.estimate_wait = sync_wait, estimate_wait
        self.awaits_estimate = estimate_wait > 0 and feedforward
        self.controller: LiveController | None = None
        self.refs = StampedBuffer()     # the reference may run ahead of the states
        self.pending = None             # (state, wall time it came)
        self.prepared = None            # ReferenceTerms of the next stamp (prepare_next)
        self.prepared_used = 0          # commands whose reference terms were prepared ahead
        self.est_stamp = None           # newest estimate stamp received (valid or not)
        self.estimates_rejected = 0
        self.skips = SkipLog()

    def describe(self, cdpr, gravity: float, config: ControllerConfig) -> None:
        """The plant's cdpr section (None: the description has none) and the controller's options
        (:func:`controller_config`) configure the law."""
        if cdpr is None:
            self.skips.last_problem = "plant description has no cdpr section"
            return
        self.controller = LiveController(cdpr, gravity, config)

    def reference(self, t: float, position, quat_wxyz, velocity, acceleration) -> None:
        self.refs.push(t, (position, quat_wxyz, velocity, acceleration))

    def references(self, t, position, quat_wxyz, velocity, acceleration) -> None:
        """k samples at once: :meth:`reference` of each row of (k,) stamps and (k, 3) / (k, 4)
        arrays (a velocity or acceleration row of NaN: none, which the law takes as zero)."""
        for row in zip(t.tolist(), position, quat_wxyz, velocity, acceleration):
            self.refs.push(row[0], row[1:])

    def estimate(self, t: float, mass: float | None, com, prepare: bool = True) -> None:
        """An estimate of stamp ``t`` (``mass`` None: the message was rejected). The terms
        prepared with the previous mass are prepared anew now, off the state -> command path, or
        (``prepare`` False: the states are answered elsewhere, as by the compiled path) dropped,
        to be prepared when a state needs them."""
        self.est_stamp = t if self.est_stamp is None else max(self.est_stamp, t)
        if mass is None or self.controller is None:
            return
        if self.controller.estimate(t, mass, com[:2]):
            old, self.prepared = self.prepared, None
            ref = None if old is None or not prepare else self.refs.at(old.t)
            if ref is not None:
                self._prepare(ref)
        else:
            self.estimates_rejected += 1

    def state(self, state, now: float) -> None:
        """Keep a motor state ``(t, names, position, velocity, effort)`` received at wall ``now``."""
        self.pending = (state, now)

    def needs_inputs_first(self, t: float) -> bool:
        """Whether the queued reference and estimate must be taken before the state of stamp ``t``
        is commanded (its reference terms were not prepared ahead, or a state is still waiting)."""
        return self.pending is not None or self.prepared_for(t) is None

    def prepared_for(self, t: float):
        """The reference terms prepared ahead if they are those of stamp ``t``, else None."""
        ref = self.prepared
        return ref if ref is not None and abs(ref.t - t) <= 1e-9 else None

    def waiting_for(self, t: float) -> tuple[bool, bool]:
        """(reference of stamp t not here yet, estimate of stamp t awaited and not here yet)."""
        ref = bool(self.refs) and self.refs.newest < t - 1e-9
        est = self.awaits_estimate and (self.est_stamp is None or self.est_stamp < t - 1e-9)
        return ref, est

    def ready(self, now: float | None = None):
        """The pending state if it can be commanded now, else None. ``now`` (the timer): also
        when it waited longer than ``sync_wait`` for its reference or ``estimate_wait`` for its
        estimate."""
        if self.pending is None:
            return None
        state, came = self.pending
        ref, est = self.waiting_for(state[0])
        if ref or est:
            age = None if now is None else now - came
            if age is None or not ((ref and age > self.sync_wait) or (not ref and age > self.estimate_wait)):
                return None
        self.pending = None
        return state

    def prepare_next(self, t: float) -> None:
        """Prepare the reference terms of the next stamp after ``t`` (not with ``estimate_wait``:
        the estimate of that stamp is not here yet)."""
        if self.controller is None or self.estimate_wait > 0 or not np.isfinite(t):
            return
        nxt = self.refs.after(t)
        if nxt is not None and self.prepared_for(nxt[0]) is None:
            self._prepare(nxt)

    def _prepare(self, ref) -> None:
        """Prepare the reference terms of ``ref`` = (stamp, (position, quat, velocity,
        acceleration)) with the present estimate."""
        stamp, (pos, quat, vel, acc) = ref
        self.prepared = self.controller.prepare(stamp, pos, quat, vel, acc)

    def report(self, level: int, msg: str, values: dict, mode: str, commands: int) -> tuple[int, str, dict]:
        """The controller's part of /diagnostics: ERROR while no description configured the law,
        else ``(level, msg)`` raised to the law's last problem; a WARN for recently skipped
        states; ``values`` gains ``mode`` (PDFF or PD), the counts (``commands`` published) and
        the feedforward mass."""
        ctl = self.controller
        if ctl is None:
            level, msg = ERROR, self.skips.last_problem or "waiting for /plant_description"
        elif ctl.status and ctl.status[-1][0] > 0:
            level, msg = add_problem(level, msg, ctl.status[-1][0], ctl.status[-1][1])
        level, msg = self.skips.warn(level, msg)
        values.update({"mode": mode, "commands": str(commands), "skipped": str(self.skips.skipped),
                       "estimates rejected": str(self.estimates_rejected),
                       "commands prepared ahead": str(self.prepared_used),
                       "feedforward mass kg": "-" if ctl is None or ctl.mass is None else f"{ctl.mass:.1f}"})
        return level, msg, values

    def command(self, state, inputs, now: float):
        """Torques for ``state`` = (t, names, position, velocity, effort) when it can be commanded
        (checked in this order): a law configured by a description, a good motor state (the
        node's input monitor ``inputs`` accepts the positions at wall ``now``; velocities of the
        same length) and a fresh reference; else None (:attr:`skips` says why)."""
        t, _names, q, qd, _eff = state
        if self.controller is None:
            return self.skips.skip("waiting for /plant_description")
        if not inputs.accept("joint_states", q, now) or qd is None or qd.size != q.size:
            return self.skips.skip("bad motor state (NaN, empty or wrong length)")
        if not self.refs or not inputs.fresh("reference", now):
            return self.skips.skip("no fresh reference: not commanding (brakes hold)")
        return self.torques(t, q, qd)

    def torques(self, t: float, q, qd):
        """Torques for the motor state of stamp ``t`` at the reference of that stamp (prepared
        ahead when it was), or None (:attr:`skips` says why)."""
        stamp, (pos, quat, vel, acc) = self.refs.at(t)
        ref = self.prepared_for(t) if abs(stamp - t) <= 1e-9 else None
        if ref is None:
            ref = self.controller.prepare(t, pos, quat, vel, acc)       # not prepared ahead
        else:
            self.prepared_used += 1
        tau = None if ref is None else self.controller.law(ref, q, qd)
        return self.skips.skip(self.controller.status[-1][1]) if tau is None else tau
