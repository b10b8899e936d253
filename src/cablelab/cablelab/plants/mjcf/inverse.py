"""MuJoCo's inverse dynamics over a record, and regressor columns taken from it.

The generalised forces are linear in each body's ten standard inertial parameters (mass m, first
moment h = m c and rotational inertia I_o about the body frame's origin, body axes). MuJoCo's
recursive Newton-Euler (``mj_rne``) sums, over the bodies below each dof, ``cdof . f_b`` with
the body's spatial force ``f_b = M_b a_b + v_b x* (M_b v_b)`` (``cvel``, ``cacc``: spatial
velocity and acceleration with gravity as an upward acceleration of the world, ``cdof``: the
dof's motion axis, all com-based). :func:`body_columns` writes ``f_b`` per unit parameter in the
body frame and maps it onto the dofs with the same ``cdof``: every column of every body comes
from one ``mj_inverse`` + ``mj_rnePostConstraint`` pass over the record (:func:`inverse_record`),
vectorised over time afterwards. The columns are exactly ``tau(theta + e_k) - tau(theta)`` (the
tests check them against those differences of ``mj_inverse``).

``mj_inverse`` has no batched form (``mujoco.rollout`` and ``mujoco.batch`` run forward only):
the pass loops over the samples with one MuJoCo call per sample and array copies, nothing else
per sample in Python.
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np

#: the ten standard inertial parameters of a body, in column order
STANDARD_PARAMS = ("m", "hx", "hy", "hz", "Ixx", "Iyy", "Izz", "Ixy", "Ixz", "Iyz")


@dataclass(frozen=True)
class InverseRecord:
    """MuJoCo's inverse dynamics of a record and the kinematics its columns are built from.

    Attributes:
        tau: (N, nv) ``qfrc_inverse``; ten_j: (N, ntendon, nv) tendon Jacobians or None;
        ten_length: (N, ntendon) the tendons' lengths at q (rigid cables), or None.
        xpos (N, nbody, 3), xmat (N, nbody, 3, 3): body frames; subtree_com (N, nbody, 3);
        cdof (N, nv, 6), cvel and cacc (N, nbody, 6): com-based (rotation : translation),
        or None when only ``tau`` was asked for.
    """

    tau: np.ndarray
    ten_j: np.ndarray | None = None
    ten_length: np.ndarray | None = None
    xpos: np.ndarray | None = None
    xmat: np.ndarray | None = None
    subtree_com: np.ndarray | None = None
    cdof: np.ndarray | None = None
    cvel: np.ndarray | None = None
    cacc: np.ndarray | None = None


def inverse_record(model, q, qd, qdd, *, tendons=False, kinematics=True) -> InverseRecord:
    """One pass of ``mj_inverse`` over a record (hinge and slide joints: nq = nv).

    Args:
        model: :class:`mujoco.MjModel`; q, qd, qdd: (N, nv) in dof order.
        tendons: also keep the tendon Jacobians ``ten_J`` and lengths ``ten_length``.
        kinematics: also run ``mj_rnePostConstraint`` and keep what :func:`body_columns` needs.
    """
    import mujoco

    q, qd, qdd = (np.ascontiguousarray(a, dtype=float) for a in (q, qd, qdd))
    n, nv = q.shape
    nb = model.nbody
    data = mujoco.MjData(model)
    tau = np.empty((n, nv))
    tj = np.empty((n, model.ntendon, nv)) if tendons else None
    tl = np.empty((n, model.ntendon)) if tendons else None
    kin = {k: np.empty((n,) + shape) for k, shape in
           (("xpos", (nb, 3)), ("xmat", (nb, 9)), ("subtree_com", (nb, 3)), ("cdof", (nv, 6)),
            ("cvel", (nb, 6)), ("cacc", (nb, 6)))} if kinematics else {}
    inv, post = mujoco.mj_inverse, mujoco.mj_rnePostConstraint
    qpos, qvel, qacc, res, ten_j = data.qpos, data.qvel, data.qacc, data.qfrc_inverse, data.ten_J
    ten_len = data.ten_length
    fields = [(kin[k], getattr(data, k)) for k in kin]
    for i in range(n):
        qpos[:] = q[i]
        qvel[:] = qd[i]
        qacc[:] = qdd[i]
        inv(model, data)
        tau[i] = res
        if tendons:
            tj[i] = ten_j.reshape(model.ntendon, nv)
            tl[i] = ten_len
        if kinematics:
            post(model, data)
            for dst, src in fields:
                dst[i] = src
    if kinematics:
        kin["xmat"] = kin["xmat"].reshape(n, nb, 3, 3)
    return InverseRecord(tau=tau, ten_j=tj, ten_length=tl, **kin)


def inverse_dynamics(model, q, qd, qdd, *, tendons=False):
    """Generalised forces ``qfrc_inverse`` (N, nv) that produce the accelerations ``qdd`` at
    ``(q, qd)`` (hinge and slide joints: nq = nv).

    Args:
        model: :class:`mujoco.MjModel`; q, qd, qdd: (N, nv) in dof order.
        tendons: also return the tendon Jacobians ``ten_J`` (N, ntendon, nv).
    """
    rec = inverse_record(model, q, qd, qdd, tendons=tendons, kinematics=False)
    return (rec.tau, rec.ten_j) if tendons else rec.tau


def _ancestor_dofs(model, body: int) -> np.ndarray:
    """(nv,) bool: the dofs that move ``body`` (those of the body and of its ancestors)."""
    chain = set()
    b = body
    while b > 0:
        chain.add(b)
        b = int(model.body_parentid[b])
    return np.array([int(model.dof_bodyid[j]) in chain for j in range(model.nv)], bool)


def _to_body(motion: np.ndarray, R: np.ndarray, r: np.ndarray) -> np.ndarray:
    """Com-based motion vectors (N, k, 6) -> the body frame at its origin: rotation R^T w,
    translation R^T (v + w x r), r = body origin - com-based point (world axes); R (N, 3, 3),
    r (N, 3). (A row vector times R is R^T times the column vector.)"""
    w, v = motion[..., :3], motion[..., 3:]
    lin = v + np.cross(w, r[:, None, :])
    return np.concatenate([w @ R, lin @ R], axis=-1)


def _skew(x: np.ndarray) -> np.ndarray:
    """(N, 3, 3) cross-product matrices S(x) (S(x) y = x x y) of (N, 3) vectors."""
    out = np.zeros(x.shape[:-1] + (3, 3))
    out[..., 0, 1], out[..., 0, 2], out[..., 1, 2] = -x[..., 2], x[..., 1], -x[..., 0]
    out[..., 1, 0], out[..., 2, 0], out[..., 2, 1] = x[..., 2], -x[..., 1], x[..., 0]
    return out


def _inertia_map(x: np.ndarray) -> np.ndarray:
    """(N, 3, 6) K(x): I x = K(x) (Ixx, Iyy, Izz, Ixy, Ixz, Iyz) for a symmetric I."""
    out = np.zeros(x.shape[:-1] + (3, 6))
    out[..., 0, 0], out[..., 1, 1], out[..., 2, 2] = x[..., 0], x[..., 1], x[..., 2]
    out[..., 0, 3], out[..., 1, 3] = x[..., 1], x[..., 0]
    out[..., 0, 4], out[..., 2, 4] = x[..., 2], x[..., 0]
    out[..., 1, 5], out[..., 2, 5] = x[..., 2], x[..., 1]
    return out


def _spatial_force_columns(w, v, alpha, acc) -> np.ndarray:
    """(N, 6, 10) spatial force ``M(theta) a + v x* (M(theta) v)`` per unit standard parameter
    (torque : force, body frame at its origin) from the body's spatial velocity (w, v) and
    acceleration (alpha, acc), each (N, 3). Written out with g = acc + w x v (the origin's
    classical acceleration): force = m g + (S(alpha) + S(w)^2) h, torque = h x g + I alpha +
    w x (I w)."""
    g = acc + np.cross(w, v)
    sw = _skew(w)
    out = np.empty((w.shape[0], 6, 10))
    out[:, :3, 0] = 0.0
    out[:, 3:, 0] = g
    out[:, :3, 1:4] = -_skew(g)
    out[:, 3:, 1:4] = _skew(alpha) + sw @ sw
    out[:, :3, 4:] = _inertia_map(alpha) + sw @ _inertia_map(w)
    out[:, 3:, 4:] = 0.0
    return out


def body_columns(model, rec: InverseRecord, body: int) -> np.ndarray:
    """(N, nv, 10) columns of the generalised forces for the body's standard parameters
    (:data:`STANDARD_PARAMS`) from a record's kinematics (:func:`inverse_record`): the spatial
    force per unit parameter (:func:`_spatial_force_columns`) dotted with the body-frame motion
    axes of the dofs that move the body. A body with gravity compensation (``gravcomp``) has that
    share of its weight taken by MuJoCo's passive force, which ``mj_inverse`` subtracts (on the
    dofs whose joint does not route it to its actuator, ``actuatorgravcomp``)."""
    import mujoco

    R = rec.xmat[:, body]
    r = rec.xpos[:, body] - rec.subtree_com[:, int(model.body_rootid[body])]
    vel, acc = _to_body(np.stack([rec.cvel[:, body], rec.cacc[:, body]], axis=1), R, r).transpose(1, 0, 2)
    cols = _spatial_force_columns(vel[:, :3], vel[:, 3:], acc[:, :3], acc[:, 3:])
    moving = np.flatnonzero(_ancestor_dofs(model, body))
    axes = _to_body(rec.cdof[:, moving], R, r)
    tau = np.zeros(rec.cdof.shape[:2] + (10,))
    tau[:, moving] = axes @ cols
    gc = float(model.body_gravcomp[body]) if model.ngravcomp else 0.0
    if gc and not model.opt.disableflags & mujoco.mjtDisableBit.mjDSBL_GRAVITY:
        # the weight's share gc: the columns of M a_g, a_g = -g as a translation (body axes)
        zero = np.zeros((len(R), 3))
        a_g = -np.asarray(model.opt.gravity, float) @ R
        grav = axes @ _spatial_force_columns(zero, zero, zero, a_g)
        passive = ~np.asarray(model.jnt_actgravcomp, bool)[model.dof_jntid]
        tau[:, moving] -= gc * grav * passive[moving][None, :, None]
    return tau


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
