"""PD plus model feedforward for any MuJoCo model (ROS-free): computed torque from the same
model the workbench uses, with a live payload estimate on ``payload_body``.

``qacc* = qdd_ref + kp (q_ref - q) + kd (qd_ref - qd)``; the generalised force is MuJoCo's
inverse dynamics at ``(q, qd, qacc*)`` (gravity, Coriolis, inertia, the model's passive forces),
spread over the actuators by least squares around a pretension on cable (tendon) actuators.
"""
from __future__ import annotations

import numpy as np

from .inverse import _skew_outer, set_standard_params, standard_params
from .mjcf import dof_joints, names
from .sim import actuator_moments

#: pretension of tendon actuators in the force distribution, N (cables must pull)
PRETENSION = 30.0
#: largest payload (kg) and centre-of-mass distance from its body (m) the law takes
MAX_PAYLOAD, MAX_REACH = 1e4, 100.0


class Feedforward:
    """The control law of one machine.

    Args:
        section: the ``mjcf:`` section; gravity: g, m/s^2; kp (1/s^2), kd (1/s): gains of the
            acceleration (the same for every joint).
    """

    def __init__(self, section, gravity: float, kp: float, kd: float):
        import mujoco

        self.model = section.compiled(gravity)
        self.data = mujoco.MjData(self.model)
        self.joints = dof_joints(self.model)
        self.kp, self.kd = float(kp), float(kd)
        self.body = names(self.model, "body").index(section.payload_body) if section.payload_body else None
        self.theta0 = standard_params(self.model, self.body) if self.body is not None else None
        tendon = self.model.actuator_trntype == 3
        self.c0 = np.where(tendon, -PRETENSION / np.maximum(np.abs(self.model.actuator_gear[:, 0]), 1e-12), 0.0)
        self._mj = mujoco

    def set_payload(self, m: float, com) -> None:
        """Carry a payload of ``m`` kg at ``com`` (payload body frame) in the feedforward."""
        if self.body is None or not np.isfinite(m) or not np.all(np.isfinite(com)):
            return
        c = np.asarray(com, float)
        P = _skew_outer(c)
        add = m * np.array([1.0, *c, P[0, 0], P[1, 1], P[2, 2], P[0, 1], P[0, 2], P[1, 2]])
        set_standard_params(self.model, self.body, self.theta0 + add)

    def command(self, q, qd, q_ref, qd_ref, qdd_ref) -> np.ndarray:
        """Actuator controls (nu,) in the model's actuator order."""
        m, d = self.model, self.data
        d.qpos[: m.nv] = q
        d.qvel[:] = qd
        d.qacc[:] = (np.asarray(qdd_ref, float) + self.kp * (np.asarray(q_ref, float) - q)
                     + self.kd * (np.asarray(qd_ref, float) - qd))
        self._mj.mj_inverse(m, d)
        A = actuator_moments(m, d).T
        return self.c0 + np.linalg.lstsq(A, d.qfrc_inverse - A @ self.c0, rcond=None)[0]


def sine_reference(t: float, n: int, amplitude: float, frequency: float):
    """The built-in reference: the same sine on every joint, phase-shifted per joint (rad or m)."""
    w = 2 * np.pi * frequency
    ph = np.arange(n) * np.pi / 3
    s, c = np.sin(w * t + ph) - np.sin(ph), np.cos(w * t + ph)
    return amplitude * s, amplitude * w * c, -amplitude * w * w * np.sin(w * t + ph)


def sine_trajectory(n: int, amplitude: float, frequency: float):
    """The built-in reference as a trajectory ``(tt, q0) -> (q, qd, qdd)`` ((N, n) each at ``tt``
    (N,) s since the first state, ``q0`` its positions): :func:`sine_reference` around ``q0``,
    starting there at rest offset zero (what :class:`cablelab.ros.reference.ReferencePlayer` plays)."""
    def trajectory(tt, q0):
        dq, dqd, dqdd = sine_reference(np.asarray(tt, float)[:, None], n, amplitude, frequency)
        return np.asarray(q0, float) + dq, dqd, dqdd

    return trajectory


def payload_values(m: float, com) -> np.ndarray | None:
    """``[m, cx, cy, cz]`` of a payload estimate when physical (a mass in [0, MAX_PAYLOAD] kg, a
    centre of mass within MAX_REACH m of its body, all finite), else None."""
    v = np.array([m, *np.asarray(com, float).ravel()], float)
    if v.size != 4 or not np.isfinite(v).all() or not 0.0 <= v[0] <= MAX_PAYLOAD \
            or np.abs(v[1:]).max() > MAX_REACH:
        return None
    return v
