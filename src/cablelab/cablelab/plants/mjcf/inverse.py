"""MuJoCo's inverse dynamics over a record, and regressor columns taken from it.

Every column here is a difference of ``mj_inverse`` results, not an equation written per
machine: the generalised forces are linear in each body's ten standard inertial parameters
(mass m, first moment h = m c and rotational inertia I_o about the body frame's origin), so
``tau(theta + e_k) - tau(theta)`` is exactly the column of parameter k (up to round-off).

``mj_inverse`` has no batched form (``mujoco.rollout`` runs forward only): each pass loops over
the samples with one MuJoCo call per sample and nothing else per sample in Python.
"""
from __future__ import annotations

import numpy as np

#: the ten standard inertial parameters of a body, in column order
STANDARD_PARAMS = ("m", "hx", "hy", "hz", "Ixx", "Iyy", "Izz", "Ixy", "Ixz", "Iyz")


def inverse_dynamics(model, q, qd, qdd, *, tendons=False):
    """Generalised forces ``qfrc_inverse`` (N, nv) that produce the accelerations ``qdd`` at
    ``(q, qd)`` (hinge and slide joints: nq = nv).

    Args:
        model: :class:`mujoco.MjModel`; q, qd, qdd: (N, nv) in dof order.
        tendons: also return the tendon Jacobians ``ten_J`` (N, ntendon, nv).
    """
    import mujoco

    q, qd, qdd = (np.ascontiguousarray(a, dtype=float) for a in (q, qd, qdd))
    n, nv = q.shape
    data = mujoco.MjData(model)
    out = np.empty((n, nv))
    tj = np.empty((n, model.ntendon, nv)) if tendons else None
    inv = mujoco.mj_inverse
    qpos, qvel, qacc, res = data.qpos, data.qvel, data.qacc, data.qfrc_inverse
    for i in range(n):
        qpos[:] = q[i]
        qvel[:] = qd[i]
        qacc[:] = qdd[i]
        inv(model, data)
        out[i] = res
        if tendons:
            tj[i] = data.ten_J.reshape(model.ntendon, nv)
    return (out, tj) if tendons else out


def _skew_outer(h):
    """P(h) = |h|^2 I - h h^T."""
    h = np.asarray(h, float)
    return float(h @ h) * np.eye(3) - np.outer(h, h)


def standard_params(model, body: int) -> np.ndarray:
    """(10,) standard parameters of a body from the model's mass, ipos, inertia and iquat."""
    import mujoco

    m = float(model.body_mass[body])
    c = np.array(model.body_ipos[body], float)
    R = np.empty(9)
    mujoco.mju_quat2Mat(R, np.array(model.body_iquat[body], float))
    R = R.reshape(3, 3)
    Ic = R @ np.diag(model.body_inertia[body]) @ R.T
    Io = Ic + m * _skew_outer(c)
    return np.array([m, *(m * c), Io[0, 0], Io[1, 1], Io[2, 2], Io[0, 1], Io[0, 2], Io[1, 2]])


def set_standard_params(model, body: int, theta) -> None:
    """Write a body's standard parameters into the model (mass, ipos, principal inertia, iquat).
    The inertia about the centre of mass need not be positive for ``mj_inverse``."""
    import mujoco

    m = float(theta[0])
    h = np.asarray(theta[1:4], float)
    c = h / m if m != 0 else np.zeros(3)
    Io = np.array([[theta[4], theta[7], theta[8]], [theta[7], theta[5], theta[9]],
                   [theta[8], theta[9], theta[6]]], float)
    Ic = Io - m * _skew_outer(c)
    w, V = np.linalg.eigh(Ic)
    if np.linalg.det(V) < 0:
        V[:, 0] = -V[:, 0]
    quat = np.empty(4)
    mujoco.mju_mat2Quat(quat, V.reshape(-1))
    model.body_mass[body] = m
    model.body_sameframe[body] = 0      # the inertial frame is no longer the body's (or aligned)
    model.body_ipos[body] = c
    model.body_inertia[body] = w
    model.body_iquat[body] = quat


_INERTIAL_FIELDS = ("body_mass", "body_ipos", "body_inertia", "body_iquat", "body_sameframe")


def inertial_columns(model, body: int, q, qd, qdd, base=None) -> np.ndarray:
    """(N, nv, 10) columns of the generalised forces for the body's standard parameters
    (:data:`STANDARD_PARAMS`): ``tau(theta0 + eps e_k) - tau(theta0)) / eps``, exact since the
    inverse dynamics is linear in them. ``base``: the nominal pass (N, nv) when already known.
    The model is restored before returning."""
    theta0 = standard_params(model, body)
    saved = [np.array(getattr(model, f)[body]) for f in _INERTIAL_FIELDS]
    tau0 = inverse_dynamics(model, q, qd, qdd) if base is None else base
    scale = max(float(theta0[0]), 1e-3)
    length = max(float(np.sqrt(np.sum(theta0[4:7]) / scale)), 0.05)
    steps = np.array([scale] + [scale * length] * 3 + [scale * length**2] * 6) * 1e-2
    cols = np.empty(tau0.shape + (10,))
    try:
        for k in range(10):
            th = theta0.copy()
            th[k] += steps[k]
            set_standard_params(model, body, th)
            cols[:, :, k] = (inverse_dynamics(model, q, qd, qdd) - tau0) / steps[k]
    finally:
        for f, v in zip(_INERTIAL_FIELDS, saved):
            getattr(model, f)[body] = v
    return cols


def point_mass_columns(inertial: np.ndarray, point) -> np.ndarray:
    """(N, nv, 4) columns of a point mass added at ``point`` (body frame) of the body whose
    standard-parameter columns are ``inertial`` (N, nv, 10): the mass column
    ``Y(p) = Y_m + Y_h p + Y_I vec(P(p))`` and its derivatives along x, y, z (the first moment
    of the mass about ``point``), P(p) = |p|^2 I - p p^T."""
    p = np.asarray(point, float)

    def vec(P):
        return np.array([P[0, 0], P[1, 1], P[2, 2], P[0, 1], P[0, 2], P[1, 2]])

    w_mass = np.concatenate([[1.0], p, vec(_skew_outer(p))])
    ws = [w_mass]
    for k in range(3):
        e = np.eye(3)[k]
        dP = 2.0 * p[k] * np.eye(3) - (np.outer(e, p) + np.outer(p, e))
        ws.append(np.concatenate([[0.0], e, vec(dP)]))
    return inertial @ np.array(ws).T
