"""Simulation of the suspended platforms on ``mujoco.rollout`` (spec 000_suspended.md sec. 4).

* :func:`initial_state`: full physics state of a model with named joint positions set (virtual
  joints ``J7..J12``, arm joints ``left_i`` / ``right_i``, or the truth platform's start swing).
* :func:`simulate`: one or many open-loop runs in one :func:`mujoco.rollout.rollout` batch;
  returns platform pose sensors (pos, quat w x y z) per step. Arm references are ctrl of the
  arm position servos. The LiCAS ``paper`` levelling needs the state each step and runs
  :func:`simulate_paper_levelling` (Python step loop, the one exception).
* :func:`outputs`: the 000 eq. 4 channels ``r_x, r_y, yaw`` (pose-based, D7) of a run.
* :func:`platform_imu`: what an IMU on the platform (LiCAS BNO055 on the shoulder structure,
  spec 5) reads: gyro and accelerometer in the platform frame.
* :class:`LiveSim`: one model stepped period by period with the arm inputs held (the simulator
  node's physics) and :class:`Reading`, what its sensors read after a period.
"""
from __future__ import annotations

from dataclasses import dataclass

import mujoco
import mujoco.rollout
import numpy as np

from .mjcf import VJ, arm_joint_names, build_truth, build_virtual, levelling_ctrl
from .params import VirtualParams, parameter_set
from .swing import CHANNELS, swing_from_pose

__all__ = ["initial_state", "simulate", "simulate_paper_levelling", "Run", "outputs",
           "truth_start", "platform_imu", "STATE_SPEC", "LiveSim", "Reading"]

STATE_SPEC = mujoco.mjtState.mjSTATE_FULLPHYSICS


@dataclass
class Run:
    """A simulated run: ``t`` (N,) s, ``pos`` (N, 3) m, ``quat`` (N, 4) w x y z, ``qpos`` (N, nq),
    all of the same instants."""

    t: np.ndarray
    pos: np.ndarray
    quat: np.ndarray
    qpos: np.ndarray | None = None


def _state(model, data) -> np.ndarray:
    x = np.empty(mujoco.mj_stateSize(model, STATE_SPEC))
    mujoco.mj_getState(model, data, x, STATE_SPEC)
    return x


def initial_state(model: mujoco.MjModel, q: dict | None = None, qd: dict | None = None,
                  free_pos=None, free_quat=None) -> np.ndarray:
    """Full physics state with joint positions/velocities by name (others 0 / the model default)."""
    d = mujoco.MjData(model)
    for name, v in (q or {}).items():
        d.qpos[model.joint(name).qposadr[0]] = v
    for name, v in (qd or {}).items():
        d.qvel[model.joint(name).dofadr[0]] = v
    if free_pos is not None:
        d.qpos[:3] = free_pos
    if free_quat is not None:
        d.qpos[3:7] = free_quat
    mujoco.mj_forward(model, d)
    return _state(model, d)


def truth_start(model: mujoco.MjModel, p: VirtualParams, swing_x=0.0, swing_y=0.0, yaw=0.0) -> np.ndarray:
    """State of the LiCAS truth plant displaced as a translational pendulum: platform level at
    ``S + Rx(swing_x) Ry(swing_y) [0, 0, -L]``, rotated by ``yaw`` about z (cables taut in the
    swing; a yaw start lifts it by the quadrifilar geometry, placed at its exact height)."""
    S = np.array(p.S, float)
    cx, sx, cy, sy = np.cos(swing_x), np.sin(swing_x), np.cos(swing_y), np.sin(swing_y)
    d = p.L * np.array([-sy, cy * sx, -cy * cx])
    pos = S + d
    if yaw:
        # a point at radius r turned by yaw: horizontal chord c = 2 r sin(yaw/2); height drop
        # sqrt(L^2 - c^2) instead of L (all four cables stay taut by symmetry)
        r = np.linalg.norm(model.site("bot0").pos[:2])
        c = 2 * r * np.sin(yaw / 2)
        pos = S - [0, 0, np.sqrt(p.L ** 2 - c ** 2) - 1e-7]
    quat = np.array([np.cos(yaw / 2), 0, 0, np.sin(yaw / 2)])
    return initial_state(model, free_pos=pos, free_quat=quat)


def simulate(model: mujoco.MjModel | list, x0, duration: float, ctrl=None, *, nthread: int = 1) -> list[Run]:
    """Open-loop runs in one rollout batch.

    Args:
        model: one model or a list (one per run, same sizes). x0: (nstate,) or (k, nstate).
        duration: s. ctrl: None (zeros), (nu,), (nstep, nu) or (k, nstep, nu) actuator ctrl.
    Returns:
        list of :class:`Run` (t = 0 .. duration - dt; pose sensors and qpos of the same instant).
    """
    models = model if isinstance(model, (list, tuple)) else [model]
    m0 = models[0]
    x0 = np.atleast_2d(np.asarray(x0, float))
    k = max(len(models), x0.shape[0])
    nstep = int(round(duration / m0.opt.timestep))
    if ctrl is None:
        ctrl = np.zeros((1, 1, m0.nu))
    ctrl = np.asarray(ctrl, float)
    if ctrl.ndim == 1:
        ctrl = ctrl[None, None, :]
    elif ctrl.ndim == 2:
        ctrl = ctrl[None]
    if ctrl.shape[1] == 1 and nstep > 1:
        ctrl = np.repeat(ctrl, nstep, axis=1)
    if len(models) == 1 and k > 1:
        models = models * k
    datas = [mujoco.MjData(m0) for _ in range(max(1, nthread))]
    state, sens = mujoco.rollout.rollout(models, datas, np.broadcast_to(x0, (k, x0.shape[1])).copy(),
                                         np.broadcast_to(ctrl, (k,) + ctrl.shape[1:]).copy(), nstep=nstep)
    # rollout's sensordata of step i is computed from the state before that step (mj_forward
    # runs first): pair it with the state at the same time, t = i dt
    t = m0.opt.timestep * np.arange(nstep)
    nq = m0.nq
    x0b = np.broadcast_to(x0, (k, x0.shape[1]))
    qpos = np.concatenate([x0b[:, None, 1:1 + nq], state[:, :-1, 1:1 + nq]], axis=1)
    return [Run(t, sens[i, :, 0:3], sens[i, :, 3:7], qpos[i]) for i in range(k)]


def simulate_paper_levelling(model: mujoco.MjModel, p: VirtualParams, x0, duration: float,
                             arm_ctrl=None) -> Run:
    """Run the ``levelling="paper"`` LiCAS model: J11/J12 motor ctrl from the state (repo
    ShouldersControlPlugin, spec 4.3) through ``mjcb_control``, so every RK4 stage sees it.
    Python step loop (state feedback, not open loop)."""
    d = mujoco.MjData(model)
    mujoco.mj_setState(model, d, np.asarray(x0, float), STATE_SPEC)
    mujoco.mj_forward(model, d)
    names = [model.joint(i).name for i in range(model.njnt)]
    # locked (absent) virtual joints read as 0: index nq / nv of a padded copy
    jq = [model.joint(j).qposadr[0] if j in names else model.nq for j in VJ]
    jv = [model.joint(j).dofadr[0] if j in names else model.nv for j in VJ]
    acts = [model.actuator(i).name for i in range(model.nu)]
    lvl = [acts.index(a) for a in ("level_J11", "level_J12") if a in acts]
    lvl_of = [k for k, a in enumerate(("level_J11", "level_J12")) if a in acts]
    arm_ids = [i for i in range(model.nu) if i not in lvl]
    nstep = int(round(duration / model.opt.timestep))
    pos = np.empty((nstep, 3))
    quat = np.empty((nstep, 4))
    qpos = np.empty((nstep, model.nq))
    ac = np.zeros(len(arm_ids)) if arm_ctrl is None else np.asarray(arm_ctrl, float)
    ac = np.broadcast_to(ac, (nstep, len(arm_ids))) if ac.ndim == 1 else ac

    def control(m, dd):
        # evaluated inside every mj_forward, so RK4 sees the feedback at each stage
        qp, qv = np.append(dd.qpos, 0.0), np.append(dd.qvel, 0.0)
        dd.ctrl[lvl] = levelling_ctrl(p, qp[jq], qv[jv])[lvl_of]

    mujoco.set_mjcb_control(control)
    try:
        for i in range(nstep):
            if arm_ids:
                d.ctrl[arm_ids] = ac[i]
            qpos[i] = d.qpos
            mujoco.mj_step(model, d)
            pos[i], quat[i] = d.sensordata[:3], d.sensordata[3:7]   # of the state before the step
    finally:
        mujoco.set_mjcb_control(None)
    return Run(model.opt.timestep * np.arange(nstep), pos, quat, qpos)


def outputs(run: Run, S, rest_pos, rest_yaw: float = 0.0) -> np.ndarray:
    """(N, 3) 000 eq. 4 outputs ``[r_x, r_y, yaw]`` of a run against a known rest pose."""
    s = swing_from_pose(run.pos, run.quat, S, rest_pos=rest_pos, rest_yaw=rest_yaw)
    return np.stack([s["r_x"], s["r_y"], s["yaw"]], axis=1)


def platform_imu(model: mujoco.MjModel, data: mujoco.MjData, site: int) -> tuple[np.ndarray, np.ndarray]:
    """(angular velocity rad/s, specific force m/s^2), both in the frame of ``site`` (id), as a
    strapdown IMU there reads them: the gyro is the site's angular velocity, the accelerometer
    its linear acceleration minus gravity (a platform at rest reads +g up), exactly MuJoCo's
    ``gyro`` / ``accelerometer`` sensors (:func:`mujoco.mj_objectVelocity` /
    :func:`mujoco.mj_objectAcceleration`, local frame). Needs ``mj_forward`` done on ``data``."""
    vel = np.zeros(6)
    acc = np.zeros(6)
    mujoco.mj_objectVelocity(model, data, mujoco.mjtObj.mjOBJ_SITE, site, vel, 1)
    mujoco.mj_rnePostConstraint(model, data)
    mujoco.mj_objectAcceleration(model, data, mujoco.mjtObj.mjOBJ_SITE, site, acc, 1)
    return vel[:3].copy(), acc[3:].copy()


@dataclass
class Reading:
    """What the sensors of a :class:`LiveSim` read at time ``t`` (s): platform ``pos`` (3,) m
    (``pos_measured`` with the pose noise), ``quat`` (4,) w x y z, arm joints ``q``, ``qd``,
    ``effort`` (actuator torque, N m), IMU ``gyro`` rad/s and ``acc`` m/s^2 in the platform frame
    (None without the IMU), the truth ``swing`` (values of :data:`~.swing.CHANNELS`) and the
    virtual joints ``J7..J12`` (None for the truth plant)."""

    t: float
    pos: np.ndarray
    pos_measured: np.ndarray
    quat: np.ndarray
    q: np.ndarray
    qd: np.ndarray
    effort: np.ndarray
    gyro: np.ndarray | None
    acc: np.ndarray | None
    swing: list
    virtual: np.ndarray | None


class LiveSim:
    """The virtual-joint model (``kind="virtual"``) or the four-tendon truth plant
    (``kind="truth"``) of parameter set ``p``, advanced one period (1/``rate`` s) at a time with
    the arm inputs held: position servo references, or torques with ``arm_motors``.

    Args:
        p: parameter set. kind: ``virtual`` or ``truth``. arm_motors: torque motors instead of
        position servos. start: initial swing about x, y and yaw, rad. rate: periods per
        second, Hz. pose_noise: standard deviation of the measured position, m. seed: of the noise.
    """

    def __init__(self, p: VirtualParams, kind: str = "virtual", *, arm_motors: bool = False,
                 start=(0.0, 0.0, 0.0), rate: float = 100.0, pose_noise: float = 0.0, seed: int = 0):
        sx, sy, yaw = start
        if kind == "truth":
            self.model = build_truth(p, arm_motors=arm_motors)
            x0 = truth_start(self.model, p, sx, sy, yaw)
        elif kind == "virtual":
            self.model = build_virtual(p, arm_motors=arm_motors)
            q0 = {"J8": sx, "J9": sy, "J7": yaw}
            if p.level_to_swing:
                q0.update({"J11": -sx, "J12": -sy})
            x0 = initial_state(self.model, q0)
        else:
            raise ValueError(f"model kind {kind!r}: expected 'virtual' or 'truth'")
        self.p = p
        self.data = mujoco.MjData(self.model)
        mujoco.mj_setState(self.model, self.data, x0, STATE_SPEC)
        mujoco.mj_forward(self.model, self.data)
        self.names = list(arm_joint_names(p))
        self.jq = [self.model.joint(n).qposadr[0] for n in self.names]
        self.jv = [self.model.joint(n).dofadr[0] for n in self.names]
        self.vq = [self.model.joint(j).qposadr[0] for j in VJ] if kind == "virtual" else []
        self.rest = np.array(p.S) - [0, 0, p.L]
        self.site = self.model.site("platform").id
        self.steps = max(1, int(round(1.0 / (rate * self.model.opt.timestep))))
        self.noise = pose_noise
        self.rng = np.random.default_rng(seed)

    @classmethod
    def of_parameters(cls, v) -> "LiveSim":
        """The simulator node's plant from its validated parameters ``v``
        (:data:`.nodes.parameters.SIM`)."""
        return cls(parameter_set(v.variant), v.model, arm_motors=v.arm_input == "effort", rate=v.rate,
                   start=(v.start_swing_x, v.start_swing_y, v.start_yaw), pose_noise=v.pose_noise)

    @property
    def t(self) -> float:
        return float(self.data.time)

    def hold(self, u) -> None:
        """Hold the arm inputs ``u`` (references, rad, or torques, N m; one per arm joint)."""
        self.data.ctrl[:len(self.names)] = u

    def advance(self) -> None:
        """One period of physics with the inputs held."""
        for _ in range(self.steps):
            mujoco.mj_step(self.model, self.data)

    def read(self, imu: bool = True) -> Reading:
        """The sensors now (``imu``: also the IMU's gyro and accelerometer)."""
        m, d = self.model, self.data
        mujoco.mj_forward(m, d)
        pos, quat = d.sensordata[:3].copy(), d.sensordata[3:7].copy()
        gyro, acc = platform_imu(m, d, self.site) if imu else (None, None)
        noisy = pos + (self.rng.normal(0, self.noise, 3) if self.noise > 0 else 0.0)
        sw = swing_from_pose(pos[None], quat[None], self.p.S, rest_pos=self.rest, rest_yaw=0.0)
        return Reading(float(d.time), pos, noisy, quat, d.qpos[self.jq].copy(), d.qvel[self.jv].copy(),
                       d.qfrc_actuator[self.jv].copy(), gyro, acc, [float(sw[k][0]) for k in CHANNELS],
                       d.qpos[self.vq].copy() if self.vq else None)
