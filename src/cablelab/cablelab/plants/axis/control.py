"""Single-axis control and live estimation laws (ROS-free; used by the axis node adapters).

* :func:`sine_reference`: q_ref, qd_ref, qdd_ref of ``offset + A sin(2 pi f t)``;
* :func:`pd_feedforward`: ``u = M_ff qdd_ref + Kp (q_ref - q) + Kd (qd_ref - qd)`` (the axis
  form of the PD + feedforward law of 001 eq. 14);
* :func:`regressor`: rows ``[qdd, qd, sign(qd), 1]`` of ``u - m c g sin q = M qdd + Fv qd +
  Fc sign(qd) + offset`` (the axis inverse model, see :mod:`cablelab.plants.axis`).
All vectorised over time.
"""
from __future__ import annotations

import numpy as np

from ...effects.friction import coulomb_sign

PARAMETERS = ("inertia", "viscous", "coulomb", "offset")


def sine_reference(t, amplitude: float, frequency: float, offset: float = 0.0):
    """(q, qd, qdd) of ``offset + amplitude sin(2 pi frequency t)``; t in s, frequency in Hz."""
    t = np.asarray(t, dtype=float)
    w = 2 * np.pi * frequency
    return (offset + amplitude * np.sin(w * t), amplitude * w * np.cos(w * t),
            -amplitude * w * w * np.sin(w * t))


def sine_trajectory(amplitude: float, frequency: float, offset: float = 0.0):
    """:func:`sine_reference` as a trajectory the controller plays
    (:class:`cablelab.ros.reference.ReferencePlayer`, ``absolute``): ``(t, q0) -> (q, qd, qdd)``,
    (N, 1) each, at the state stamps ``t`` (s); the first state ``q0`` is not used."""
    return lambda t, _q0: tuple(np.reshape(x, (-1, 1)) for x in sine_reference(t, amplitude, frequency, offset))


def pd_feedforward(q, qd, q_ref, qd_ref, qdd_ref, kp: float, kd: float, inertia: float = 0.0):
    """Motor force/torque of PD + inertia feedforward (N or N m)."""
    return (inertia * np.asarray(qdd_ref) + kp * (np.asarray(q_ref) - np.asarray(q))
            + kd * (np.asarray(qd_ref) - np.asarray(qd)))


def regressor(qd, qdd, eps: float = 1e-3) -> np.ndarray:
    """(N, 4) rows ``[qdd, qd, sign(qd), 1]``; ``sign`` is 0 for |qd| < eps (stiction zone)."""
    qd = np.asarray(qd, dtype=float).reshape(-1)
    qdd = np.asarray(qdd, dtype=float).reshape(-1)
    return np.column_stack([qdd, qd, coulomb_sign(qd, eps), np.ones_like(qd)])


def gravity_load(q, gravity_moment: float, gravity: float = 9.81):
    """``m c g sin q`` (N m) of a revolute axis, q = 0 hanging down."""
    return gravity_moment * gravity * np.sin(np.asarray(q, dtype=float))
