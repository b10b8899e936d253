"""Arm control laws of the suspended platforms (spec 000_suspended.md sec. 5.3).

* :class:`ArmGravity`: the arms' own gravity torque under the measured platform attitude,
  ``g_arm(q, R_platform)``: :func:`mujoco.mj_rne` (zero velocity and acceleration) of an arm-only
  MuJoCo model (platform fixed) with gravity rotated into the platform frame, ``R^T g``.
* :func:`pd_gravity`: ``tau = Kp (q^d - q) + Kd (qd^d - qd) + g_arm``, saturated at the repo
  effort limits (LiCAS 10 N m).
* :func:`fig7_excitation`: the arm-induced excitation of 000 Fig. 7, sinusoids on joints 2 and
  3 at 0.25 Hz (x, y swing) or 0.33 Hz (yaw) with the amplitudes of spec 2.3. The mapping of
  axis to joints (same sign on both arms for x/y, opposite for yaw) is *proposed*.
* :func:`sway_offset`: optional sway damping by arm motion, ``delta q2^d = -k_s v_swing``
  (limited to +-0.2 rad; 0 when the swing estimate is older than 0.2 s). The arms' reaction
  then opposes the swing velocity.
* :class:`ArmLaw`: the three together, the law the controller node runs on each joint state.
"""
from __future__ import annotations

import mujoco
import numpy as np

from .mjcf import _arm_xml
from .params import VirtualParams

__all__ = ["ArmGravity", "ArmLaw", "pd_gravity", "fig7_excitation", "sway_offset", "gains", "FIG7"]

#: 000 Fig. 7 excitation: frequency (Hz) and amplitudes (deg, three levels) per target mode
FIG7 = {"x": (0.25, (11.5, 17.0, 20.0)), "y": (0.25, (11.5, 17.0, 20.0)),
        "z": (0.33, (2.85, 5.7, 8.6))}


def gains(p: VirtualParams) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """(Kp, Kd, effort limit) per arm joint, order left_1..left_n, right_1..right_n (repo yaml)."""
    kp = np.array([a.kp for a in p.arm] * 2)
    kd = np.array([a.kd for a in p.arm] * 2)
    lim = np.array([a.effort for a in p.arm] * 2)
    return kp, kd, lim


class ArmGravity:
    """Gravity torque of both arms on a fixed platform, for any platform attitude.

    Args:
        p: parameter set (arm geometry and inertias). g: gravity magnitude, m/s^2.
    """

    def __init__(self, p: VirtualParams, g: float = 9.81):
        xml = f"""<mujoco><compiler angle="radian" autolimits="true"/><option gravity="0 0 {-g!r}"/>
  <worldbody><body name="platform">
{_arm_xml(p, "left", "  ")}
{_arm_xml(p, "right", "  ")}
  </body></worldbody></mujoco>"""
        self.model = mujoco.MjModel.from_xml_string(xml)
        self.data = mujoco.MjData(self.model)
        self.g = np.array([0.0, 0.0, -g])
        self._out = np.zeros(self.model.nv)

    def torque(self, q_arm, R_platform=None) -> np.ndarray:
        """Joint torques (N m) that hold the arms still at ``q_arm`` under attitude ``R_platform``
        (3x3, platform to world; None = level)."""
        R = np.eye(3) if R_platform is None else np.asarray(R_platform, float).reshape(3, 3)
        self.model.opt.gravity[:] = R.T @ self.g
        self.data.qpos[:] = q_arm
        self.data.qvel[:] = 0.0
        mujoco.mj_kinematics(self.model, self.data)
        mujoco.mj_comPos(self.model, self.data)
        mujoco.mj_rne(self.model, self.data, 0, self._out)
        return self._out.copy()


def pd_gravity(q, qd, q_ref, qd_ref, kp, kd, g_arm, limit) -> np.ndarray:
    """``Kp (q^d - q) + Kd (qd^d - qd) + g_arm`` clipped to +-limit (N m). Works on (n,) or (N, n)."""
    tau = kp * (np.asarray(q_ref) - q) + kd * (np.asarray(qd_ref) - qd) + g_arm
    return np.clip(tau, -limit, limit)


def fig7_excitation(t, p: VirtualParams, mode: str = "y", level: int = 1):
    """Arm references (q, qd) of shape (N, 2n) for the 000 Fig. 7 excitation.

    ``mode`` ``x``/``y``: joints 2 and 3 of both arms, same sign; ``z``: opposite signs (yaw).
    ``level`` 0..2 picks the amplitude of spec 2.3.
    """
    f, amps = FIG7[mode]
    a = np.deg2rad(amps[level])
    t = np.asarray(t, float)
    w = 2 * np.pi * f
    n = p.n_arm
    q = np.zeros((t.size, 2 * n))
    qd = np.zeros_like(q)
    sign_r = -1.0 if mode == "z" else 1.0
    for j in (1, 2):                                      # joints 2 and 3
        for k, s in ((j, 1.0), (n + j, sign_r)):
            q[:, k] = s * a * np.sin(w * t)
            qd[:, k] = s * a * w * np.cos(w * t)
    return q, qd


def sway_offset(v_swing: float, k_s: float, age: float, *, limit: float = 0.2, stale: float = 0.2) -> float:
    """Sway-damping offset of the joint-2 reference, rad: ``-k_s v_swing`` clipped to +-limit;
    0 when the estimate is older than ``stale`` s or not finite."""
    if not np.isfinite(v_swing) or age > stale or k_s == 0.0:
        return 0.0
    return float(np.clip(-k_s * v_swing, -limit, limit))


class ArmLaw:
    """The arm command of one joint state: :func:`pd_gravity` towards the reference plus the
    built-in :func:`fig7_excitation` (``excitation`` ``none``/``x``/``y``/``z`` at ``level``)
    and the :func:`sway_offset` on joint 2 of both arms (gain ``sway_damping``, off for a swing
    estimate older than ``stale`` s), with the arms' gravity under the platform attitude."""

    def __init__(self, p: VirtualParams, excitation: str = "none", level: int = 1,
                 sway_damping: float = 0.0, stale: float = 0.2):
        self.p = p
        self.kp, self.kd, self.limit = gains(p)
        self.gravity = ArmGravity(p)
        self.excitation, self.level, self.k_s, self.stale = excitation, level, sway_damping, stale

    def torque(self, t: float, q, qd, q_ref, qd_ref, R=None, v_swing: float = np.nan,
               swing_age: float = np.inf) -> np.ndarray:
        """Torques (N m) at time ``t`` (s) for arm state ``q``, ``qd``, reference ``q_ref``,
        ``qd_ref``, platform attitude ``R`` (3x3, None = level) and the r_y swing rate
        ``v_swing`` (rad/s) estimated ``swing_age`` s before ``t``."""
        q_ref, qd_ref = np.array(q_ref, float), np.array(qd_ref, float)
        if self.excitation in ("x", "y", "z"):
            qe, qde = fig7_excitation(np.array([t]), self.p, self.excitation, self.level)
            q_ref, qd_ref = q_ref + qe[0], qd_ref + qde[0]
        off = sway_offset(v_swing, self.k_s, swing_age, stale=self.stale)
        q_ref[[1, self.p.n_arm + 1]] += off
        return pd_gravity(q, qd, q_ref, qd_ref, self.kp, self.kd, self.gravity.torque(q, R), self.limit)
