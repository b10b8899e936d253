"""Crane joint controller: PD + gravity compensation + reference-acceleration feedforward
(002 sec. 5.3.1), vectorised over samples (the controller node calls it with N = 1).

    tau = Kp (q_ref - q) + Kd (qd_ref - qd) + G_a(q) + M_aa(q) qdd_ref

over the actuated joints a = [slew, luff, hoist] (N m, N m, N); G and M from the symbolic model
(:mod:`.model`) with the measured swing angles when given (else a hanging payload).
With stale inputs :func:`hold_command` gives the fallback: gravity compensation at the last
measured position with velocity damping only (no PD on an old reference).
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from .model import CraneParams, gravity_vector, mass_matrix

__all__ = ["Gains", "LIVE_GAINS", "control_law", "hold_command", "joint_command", "sim_drive"]


@dataclass(frozen=True)
class Gains:
    """PD gains per actuated joint: kp [N m/rad, N m/rad, N/m], kd [N m s/rad, N m s/rad, N s/m]."""

    kp: tuple = (30.0, 40.0, 400.0)
    kd: tuple = (10.0, 12.0, 40.0)


#: gains for the live nodes: a 100 Hz loop over DDS adds one to two periods of delay, so the
#: hoist (0.5 kg payload) gets a 14 rad/s loop instead of the 28 rad/s of the 1 kHz simulation
LIVE_GAINS = Gains(kp=(20.0, 30.0, 100.0), kd=(8.0, 10.0, 10.0))


def _q5(q, swing):
    q = np.atleast_2d(np.asarray(q, dtype=float))
    out = np.zeros((q.shape[0], 5))
    out[:, :3] = q[:, :3]
    if swing is not None:
        out[:, 3:] = np.atleast_2d(np.asarray(swing, dtype=float))[:, :2]
    return out


def control_law(q, qd, q_ref, qd_ref, qdd_ref, params: CraneParams, gains: Gains = Gains(),
                swing=None, feedforward: bool = True) -> np.ndarray:
    """(N, 3) effort commands [slew N m, luff N m, hoist N] (002 sec. 5.3.1).

    Args:
        q, qd: (N, 3) measured [alpha, beta, d] and rates. q_ref, qd_ref, qdd_ref: (N, 3) reference.
        params: model parameters for G and M. swing: optional (N, 2) measured [theta1, theta2].
        feedforward: add G_a(q) + M_aa(q) qdd_ref (False: plain PD).
    """
    q = np.atleast_2d(np.asarray(q, dtype=float))
    e = np.atleast_2d(q_ref) - q
    ed = np.atleast_2d(qd_ref) - np.atleast_2d(qd)
    tau = np.asarray(gains.kp) * e + np.asarray(gains.kd) * ed
    if feedforward:
        q5 = _q5(q, swing)
        tau = tau + gravity_vector(q5, params)[:, :3]
        tau = tau + np.einsum("nij,nj->ni", mass_matrix(q5, params)[:, :3, :3], np.atleast_2d(qdd_ref))
    return tau


def hold_command(q, qd, params: CraneParams, gains: Gains = Gains(), swing=None) -> np.ndarray:
    """(N, 3) fallback when the reference or the state is stale: G_a(q) - Kd qd."""
    q5 = _q5(q, swing)
    return gravity_vector(q5, params)[:, :3] - np.asarray(gains.kd) * np.atleast_2d(qd)


def joint_command(q, qd, ref, params: CraneParams, gains: Gains = Gains(), swing=None,
                  feedforward: bool = True) -> np.ndarray:
    """(3,) efforts for one joint state ``q`` (3,), ``qd`` (3,; missing or not finite: zero):
    :func:`control_law` toward ``ref`` = (q_ref, qd_ref, qdd_ref) (3,) each, or :func:`hold_command`
    where the crane is when ``ref`` is None (stale); ``swing`` (1, 2) measured swing or None."""
    q = np.asarray(q, float)
    if qd is None or np.size(qd) != 3 or not np.isfinite(qd).all():
        qd = np.zeros(3)
    if ref is None:
        return hold_command(q[None], np.asarray(qd, float)[None], params, gains, swing)[0]
    return control_law(q[None], np.asarray(qd, float)[None], ref[0][None], ref[1][None], ref[2][None],
                       params, gains, swing, feedforward)[0]


def sim_drive(u, q, qd, params: CraneParams, *, answered: bool, fresh: bool, lockstep: bool):
    """The effort the simulated drives apply over the next period, and whether it is the hold.

    Args:
        u: (3,) the last good command, or None before the first.
        q, qd: (5,) contract state (slew, luff, hoist, theta1, theta2) and its rates.
        answered: ``u`` answers the last published state (lock-step): applied however late.
        fresh: ``u`` is younger than the command timeout.
        lockstep: lock-step is on (an unanswered step then never reuses an old command).

    Returns:
        ``(effort (3,), held)``: ``u``, or the drives holding the crane (:func:`hold_command`
        with :data:`LIVE_GAINS`, like a brake) when ``u`` is missing, stale or not an answer in
        lock-step.
    """
    if answered or (u is not None and fresh and not lockstep):
        return u, False
    q, qd = np.asarray(q, float), np.asarray(qd, float)
    return hold_command(q[None, :3], qd[None, :3], params, LIVE_GAINS, swing=q[None, 3:])[0], True
