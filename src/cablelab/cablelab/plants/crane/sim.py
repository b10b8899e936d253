"""MuJoCo model of the 5-DoF boom crane of 002 ch. 3, built from :class:`CraneTruth`.

Tree (qpos = [alpha, beta, psi, phi, d]):

* ``slew`` hinge about z; the turret (on the axis, no offset) has inertia I_tot about z (002 eq.
  A.1: 1/2 I_tot alpha_dot^2; its mass has no effect);
* ``luff`` hinge about -y (beta > 0 raises the tip), armature I_b (1/2 I_b beta_dot^2); the boom
  carries point masses m_b at l_b/2 (002 eq. A.1: 1/8 m_b |v_tip|^2) and m_c at -l_c (counterbalance);
* at the tip, a massless gimbal: ``swing_y`` (psi) about -y then ``swing_x`` (phi) about x; the
  payload body slides along -z on ``hoist`` (rope length d, rigid massless rope, assumption 2)
  and is a point mass m (assumption 3). :func:`cablelab.plants.crane.kinematics.gimbal_to_swing`
  maps (beta, psi, phi) to the swing angles of CONTRACT sec. 2.

Truth switches: base tilt (gravity rotated in the base frame, 002 sec. 6.5), joint viscous
(``damping``) and Coulomb (``frictionloss``) friction, torque sensor offset, motion-capture noise
and dropouts. Actuators are torque/force motors (``ctrl`` = slew N m, luff N m, hoist N);
:func:`simulate` closes the loop of 002 sec. 5.3.1 around them.
"""
from __future__ import annotations

import os
from dataclasses import dataclass, field

import mujoco
import numpy as np

from . import topics
from .control import sim_drive
from .kinematics import gimbal_rates_to_swing, gimbal_to_swing, swing_to_gimbal
from .mjcf import build_mjcf, gravity_in_base
from .model import CraneParams, gravity_vector, mass_matrix
from .reference import reference_trajectory
from ...description import load_description
from ...errors import CablelabError
from ...rotations import wxyz_to_xyzw

#: the simulator node's description without a ``description`` parameter
DEFAULT_DESCRIPTION = os.path.join(os.path.dirname(__file__), "data", "crane.yaml")

__all__ = ["CraneTruth", "set_state", "gravity_in_base", "simulate", "SimResult",
           "reference_trajectory", "QPOS", "contract_acceleration", "truth_accelerations",
           "contract_to_qpos", "qpos_to_contract", "DEFAULT_KP", "DEFAULT_KD", "CraneSim",
           "write_bag", "truth_from_parameters"]

QPOS = ("slew", "luff", "swing_y", "swing_x", "hoist")


@dataclass(frozen=True)
class CraneTruth:
    """Simulated crane: parameters plus the optional truth effects (all off by default).

    Args:
        params: rigid-body parameters.
        base_tilt: (2,) small rotation of the base about world x and y, rad (002 sec. 6.5).
        viscous: (3,) joint viscous friction [slew N m s/rad, luff N m s/rad, hoist N s/m].
        coulomb: (3,) joint Coulomb friction [N m, N m, N] (MuJoCo frictionloss).
        torque_offset: (3,) constant bias of the measured efforts [N m, N m, N].
        effort_noise: (3,) standard deviation of effort noise.
        mocap_noise: standard deviation of the motion-capture positions, m.
        mocap_dropout: probability that a motion-capture sample is lost (NaN pose).
        timestep: MuJoCo time step, s.
        effort_limit: (3,) drive saturation [N m, N m, N] (MuJoCo ctrlrange).
        rope_range: (2,) hoist joint limits [d_min, d_max], m (a rope never reaches 0 length).
    """

    params: CraneParams = field(default_factory=CraneParams)
    base_tilt: tuple = (0.0, 0.0)
    viscous: tuple = (0.0, 0.0, 0.0)
    coulomb: tuple = (0.0, 0.0, 0.0)
    torque_offset: tuple = (0.0, 0.0, 0.0)
    effort_noise: tuple = (0.0, 0.0, 0.0)
    mocap_noise: float = 0.0
    mocap_dropout: float = 0.0
    timestep: float = 0.001
    effort_limit: tuple = (50.0, 80.0, 100.0)
    rope_range: tuple = (0.05, 5.0)


def contract_to_qpos(q5) -> np.ndarray:
    """(N, 5) MuJoCo qpos [alpha, beta, psi, phi, d] from contract q [alpha, beta, d, theta1, theta2]."""
    q5 = np.atleast_2d(np.asarray(q5, dtype=float))
    psi, phi = swing_to_gimbal(q5[:, 1], q5[:, 3], q5[:, 4])
    return np.stack([q5[:, 0], q5[:, 1], psi, phi, q5[:, 2]], axis=1)


def qpos_to_contract(qpos, qvel=None):
    """Contract q (N, 5) (and qd when ``qvel`` is given) from MuJoCo qpos/qvel (N, 5)."""
    qpos = np.atleast_2d(np.asarray(qpos, dtype=float))
    th1, th2 = gimbal_to_swing(qpos[:, 1], qpos[:, 2], qpos[:, 3])
    q = np.stack([qpos[:, 0], qpos[:, 1], qpos[:, 4], th1, th2], axis=1)
    if qvel is None:
        return q
    qvel = np.atleast_2d(np.asarray(qvel, dtype=float))
    th1d, th2d = gimbal_rates_to_swing(qpos[:, 1], qpos[:, 2], qpos[:, 3], qvel[:, 1], qvel[:, 2], qvel[:, 3])
    return q, np.stack([qvel[:, 0], qvel[:, 1], qvel[:, 4], th1d, th2d], axis=1)


def set_state(model: mujoco.MjModel, data: mujoco.MjData, q5, qd5=None) -> None:
    """Put the crane at contract state q (5,) (swing velocities must be 0 if qd5 is given with swing)."""
    data.qpos[:] = contract_to_qpos(q5)[0]
    data.qvel[:] = 0.0
    if qd5 is not None:
        qd5 = np.asarray(qd5, dtype=float)
        data.qvel[[0, 1, 4]] = qd5[:3]
        data.qvel[2] = -qd5[1]  # keep the rope direction fixed in the slewing frame while luffing
    mujoco.mj_forward(model, data)


@dataclass
class SimResult:
    """A simulated run sampled at the recording rate (SI units).

    Attributes:
        t: (N,) s. q, qd: (N, 5) true contract coordinates [alpha, beta, d, theta1, theta2] and rates.
        effort: (N, 3) measured efforts (motor + truth friction seen by the sensor + offset + noise).
        motor: (N, 3) true actuator efforts. tip, payload: (N, 3) motion-capture positions (noise,
        NaN dropouts). tip_quat, payload_quat: (N, 4) w, x, y, z. q_ref, qd_ref, qdd_ref: (N, 3).
    """

    t: np.ndarray
    q: np.ndarray
    qd: np.ndarray
    effort: np.ndarray
    motor: np.ndarray
    tip: np.ndarray
    payload: np.ndarray
    tip_quat: np.ndarray
    payload_quat: np.ndarray
    q_ref: np.ndarray
    qd_ref: np.ndarray
    qdd_ref: np.ndarray
    qpos: np.ndarray
    qvel: np.ndarray


DEFAULT_KP = (30.0, 40.0, 400.0)
DEFAULT_KD = (10.0, 12.0, 40.0)


def simulate(truth: CraneTruth, duration: float, *, decimate: int = 10, seed: int = 0,
             reference=None, model_params: CraneParams | None = None,
             kp=DEFAULT_KP, kd=DEFAULT_KD, feedforward: bool = True) -> SimResult:
    """Closed-loop run of the crane tracking ``reference`` under PD + gravity/acceleration FF.

    The controller of 002 sec. 5.3.1 (``Kp e + Kd e_dot + G_a(q_ref) + M_aa(q_ref) qdd_ref``, the
    feedforward precomputed along the reference from ``model_params``) runs at every MuJoCo step
    with a zero-order hold, so the recorded effort is exactly the force the joint felt. (A PD in
    the actuator bias would let MuJoCo integrate the velocity-dependent part differently from the
    force it reports, which shows up as a spurious viscous friction in identification.)

    Args:
        truth: simulated crane and truth effects.
        duration: s. decimate: record every n-th MuJoCo step. seed: noise / dropout seed.
        reference: ``fn(t) -> (q_ref, qd_ref, qdd_ref)`` (N, 3) each; default
            :func:`reference_trajectory`.
        model_params: parameters of the feedforward (default: the truth's).
        feedforward: False = plain PD (no gravity compensation, no acceleration feedforward).
    """
    dt = truth.timestep
    n = int(round(duration / dt))
    t = np.arange(n) * dt
    ref = reference or reference_trajectory
    q_ref, qd_ref, qdd_ref = ref(t)
    mp = model_params or truth.params
    q5 = np.zeros((n, 5))
    q5[:, :3] = q_ref
    G = gravity_vector(q5, mp)[:, :3]
    M = mass_matrix(q5, mp)[:, :3, :3]
    kp, kd = np.asarray(kp, float), np.asarray(kd, float)
    u0 = kp * q_ref + kd * qd_ref
    if feedforward:
        u0 = u0 + G + np.einsum("nij,nj->ni", M, qdd_ref)
    model = build_mjcf(truth)
    data = mujoco.MjData(model)
    set_state(model, data, [q_ref[0, 0], q_ref[0, 1], q_ref[0, 2], 0.0, 0.0])
    idx = np.array([0, 1, 4])
    rec = np.arange(0, n, decimate)
    m = rec.shape[0]
    qpos, qvel = np.empty((m, model.nq)), np.empty((m, model.nv))
    sens = np.empty((m, model.nsensordata))
    j = 0
    for k in range(n):  # the control loop (feedback at every step, zero-order hold)
        u = u0[k] - kp * data.qpos[idx] - kd * data.qvel[idx]
        data.ctrl[:] = u
        if k % decimate == 0:
            qpos[j], qvel[j] = data.qpos, data.qvel
        mujoco.mj_step(model, data)
        if k % decimate == 0:
            sens[j] = data.sensordata  # computed at the state before the step
            j += 1
    tt = t[rec]
    q, qd = qpos_to_contract(qpos, qvel)
    rng = np.random.default_rng(seed)
    motor = sens[:, 6:9]
    effort = motor + np.asarray(truth.torque_offset, float) + rng.normal(size=motor.shape) * np.asarray(truth.effort_noise, float)
    tip, tipq, pay, payq = sens[:, 13:16].copy(), sens[:, 16:20], sens[:, 20:23].copy(), sens[:, 23:27]
    if truth.mocap_noise > 0:
        tip += rng.normal(scale=truth.mocap_noise, size=tip.shape)
        pay += rng.normal(scale=truth.mocap_noise, size=pay.shape)
    if truth.mocap_dropout > 0:
        lost = rng.random(len(tt)) < truth.mocap_dropout
        tip[lost] = np.nan
        pay[lost] = np.nan
    return SimResult(t=tt, q=q, qd=qd, effort=effort, motor=motor, tip=tip, payload=pay,
                     tip_quat=tipq, payload_quat=payq, q_ref=q_ref[rec],
                     qd_ref=qd_ref[rec], qdd_ref=qdd_ref[rec], qpos=qpos, qvel=qvel)


def contract_acceleration(qpos, qvel, qacc, step: float = 1e-6) -> np.ndarray:
    """(N, 5) contract qdd = J qacc + Jdot qvel of the gimbal -> swing map (vectorised).

    J a is :func:`gimbal_rates_to_swing` (exact, linear in the rates); Jdot v is its directional
    derivative along v by a central difference of step ``step`` (relative error ~1e-10).
    """
    qpos, qvel, qacc = (np.atleast_2d(np.asarray(x, dtype=float)) for x in (qpos, qvel, qacc))

    def rates(x, v):
        return np.stack(gimbal_rates_to_swing(x[:, 1], x[:, 2], x[:, 3], v[:, 1], v[:, 2], v[:, 3]), 1)

    ja = rates(qpos, qacc)
    jdv = (rates(qpos + step * qvel, qvel) - rates(qpos - step * qvel, qvel)) / (2 * step)
    sw = ja + jdv
    return np.stack([qacc[:, 0], qacc[:, 1], qacc[:, 4], sw[:, 0], sw[:, 1]], axis=1)


def truth_accelerations(truth: CraneTruth, res: SimResult) -> np.ndarray:
    """(N, 5) exact contract accelerations of a :class:`SimResult` (MuJoCo forward dynamics at
    each recorded state with the recorded motor efforts; ground truth for tests and benchmarks)."""
    model = build_mjcf(truth)
    data = mujoco.MjData(model)
    qacc = np.empty_like(res.qvel)
    for k in range(res.qpos.shape[0]):  # MuJoCo has no batched mj_forward; ground truth only
        data.qpos[:], data.qvel[:], data.ctrl[:] = res.qpos[k], res.qvel[k], res.motor[k]
        mujoco.mj_forward(model, data)
        qacc[k] = data.qacc
    return contract_acceleration(res.qpos, res.qvel, qacc)


class CraneSim:
    """Step-wise crane simulation for the simulator node (MuJoCo, motor actuators).

    ``advance(u, duration)`` holds the effort command ``u`` = [slew N m, luff N m, hoist N] for
    ``duration`` s; :meth:`measurement` returns what the sensors read at the current state.
    """

    def __init__(self, truth: CraneTruth, q0=(0.0, 0.5, 0.6), seed: int = 0):
        self.truth = truth
        self.model = build_mjcf(truth)
        self.data = mujoco.MjData(self.model)
        self.rng = np.random.default_rng(seed)
        set_state(self.model, self.data, [q0[0], q0[1], q0[2], 0.0, 0.0])
        self.u = np.zeros(3)
        self.resets = 0  # divergences recovered (see advance)
        self.held = 0    # periods the drives held the crane (see drive)

    @property
    def time(self) -> float:
        return float(self.data.time)

    t = time    #: the sim time, s (as the other plants' simulators name it)

    def advance(self, u, duration: float) -> None:
        u = np.asarray(u, dtype=float).reshape(3)
        self.u = u
        self.data.ctrl[:] = u
        steps = max(1, int(round(duration / self.model.opt.timestep)))
        t0, qpos0 = self.data.time, self.data.qpos.copy()
        for _ in range(steps):  # MuJoCo stepping with a held command (mj_step per time step)
            mujoco.mj_step(self.model, self.data)
        ok = (self.data.time > t0 and np.all(np.isfinite(self.data.qpos))
              and np.all(np.isfinite(self.data.qvel)) and np.abs(self.data.qvel).max() < 1e3)
        if not ok:
            # MuJoCo resets an unstable simulation to qpos0 (rope length 0): restore the last
            # good state at rest instead, keep the clock running, and count it
            self.resets += 1
            self.data.qpos[:], self.data.qvel[:] = qpos0, 0.0
            self.data.time = t0 + steps * self.model.opt.timestep
        mujoco.mj_forward(self.model, self.data)

    def drive(self, u, duration: float, *, answered: bool, fresh: bool, lockstep: bool) -> bool:
        """Advance ``duration`` s with the drives of :func:`.control.sim_drive` (``u``: the last
        good command, None before the first; ``answered``, ``fresh``, ``lockstep`` as there): ``u``,
        or the drives holding the crane when it is missing, stale or, in lock-step, not the
        answer to the last state. True for the hold (counted in :attr:`held`)."""
        _, q, qd = self.state()
        effort, held = sim_drive(u, q, qd, self.truth.params, answered=answered, fresh=fresh,
                                 lockstep=lockstep)
        self.held += held
        self.advance(effort, duration)
        return held

    def state(self) -> tuple[float, np.ndarray, np.ndarray]:
        """(t s, contract q (5,), qd (5,)) - simulation truth."""
        q, qd = qpos_to_contract(self.data.qpos[None], self.data.qvel[None])
        return self.time, q[0], qd[0]

    def measurement(self) -> dict:
        """Sensor readings: ``joints`` (3,), ``joint_rates`` (3,), ``effort`` (3,) = command + offset
        + noise, ``tip``/``payload`` positions (3,) (NaN on a dropout) and quaternions (4,) x, y, z, w."""
        tr = self.truth
        s = self.data.sensordata
        eff = self.u + np.asarray(tr.torque_offset, float) + self.rng.normal(size=3) * np.asarray(tr.effort_noise, float)
        tip, pay = s[13:16].copy(), s[20:23].copy()
        if tr.mocap_noise > 0:
            tip += self.rng.normal(scale=tr.mocap_noise, size=3)
            pay += self.rng.normal(scale=tr.mocap_noise, size=3)
        if tr.mocap_dropout > 0 and self.rng.random() < tr.mocap_dropout:
            tip[:] = np.nan
            pay[:] = np.nan
        return {"joints": s[0:3].copy(), "joint_rates": s[3:6].copy(), "effort": eff,
                "tip": tip, "tip_quat": wxyz_to_xyzw(s[16:20]), "payload": pay,
                "payload_quat": wxyz_to_xyzw(s[23:27])}


def truth_from_parameters(node: str, params: CraneParams, v) -> tuple[CraneTruth, tuple]:
    """The simulated crane's truth and initial ``(slew, luff, rope length)`` from the validated
    simulator node parameters ``v`` (:data:`cablelab.plants.crane.nodes.parameters.SIM`); a
    one-line error naming ``node`` for a rope length that is not positive."""
    q0 = tuple(v.initial)
    if q0[2] <= 0:
        raise CablelabError(f"{node}: parameter initial:={list(q0)}: expected a rope "
                            "length (third value) > 0 [m]")
    return CraneTruth(params=params, base_tilt=tuple(v.base_tilt), viscous=tuple(v.viscous),
                      coulomb=tuple(v.coulomb), torque_offset=tuple(v.offset),
                      mocap_noise=v.mocap_noise, mocap_dropout=v.mocap_dropout,
                      timestep=v.timestep), q0


def live_sim(node: str, v):
    """``(description, CraneSim)`` of the simulator node's validated parameters ``v``
    (:data:`.nodes.parameters.SIM`: its ``description`` or :data:`DEFAULT_DESCRIPTION`, the
    inertias it does not hold, the truth of :func:`truth_from_parameters`); a one-line error
    naming ``node`` for a description without a crane section."""
    desc = load_description(v.description or DEFAULT_DESCRIPTION)
    if desc.crane is None:
        raise CablelabError(f"{node} --plant crane: the description has no crane section")
    params = CraneParams.from_description(desc, slew_inertia=v.slew_inertia, luff_inertia=v.luff_inertia)
    return desc, CraneSim(*truth_from_parameters(node, params, v))


def write_bag(path, res: SimResult, description_yaml: str, *, overwrite: bool = False) -> None:
    """Write a simulated run as a contract bag (CONTRACT sec. 2 crane topics + /clock +
    /plant_description); mocap quaternions are stored x, y, z, w."""
    from ...bags import BagWriter

    with BagWriter(path, overwrite=overwrite) as w:
        w.write_description(description_yaml)
        w.write_clock(res.t)
        w.write_joint_states(topics.JOINT_STATES, res.t, ("slew", "luff", "hoist"),
                             position=res.q[:, :3], velocity=res.qd[:, :3], effort=res.effort)
        w.write_poses(topics.TIP_POSE, res.t, res.tip, wxyz_to_xyzw(res.tip_quat))
        w.write_poses(topics.PAYLOAD_POSE, res.t, res.payload, wxyz_to_xyzw(res.payload_quat))
        w.write_joint_states(topics.SWING_TRUTH, res.t, ("theta1", "theta2", "rope_length"),
                             position=res.q[:, [3, 4, 2]], velocity=res.qd[:, [3, 4, 2]])
        w.write_joint_trajectory(topics.REFERENCE, res.t, ("slew", "luff", "hoist"), res.q_ref,
                                 res.qd_ref, res.qdd_ref)
        w.write_float_arrays(topics.EFFORT_COMMANDS, res.t, res.motor)
