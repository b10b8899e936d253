"""Forward simulation of an ``mjcf`` machine (ROS-free): the truth a bag is recorded from.

This is deliberately a separate path from the workbench's inverse dynamics: the truth model is
the user's model *changed through MuJoCo's own model editor* (:class:`mujoco.MjSpec`: a payload
body added, joint damping, Coulomb friction (``frictionloss``) or armature set, a wrong torque
constant on the effort sensor), stepped forward by ``mj_step`` under a PD tracking controller,
and recorded with encoder quantisation and effort noise, so the record is the machine's motion
and nothing of the workbench's code.

Two ways of stepping it:

- one physics step per sample (default): MuJoCo's explicit Euler with implicit damping disabled,
  the control held over the step. The recorded positions' second difference is then exactly the
  acceleration MuJoCo computed, but the state's velocity is the backward difference
  ``(q[k] - q[k-1]) / dt``, half a step behind the positions' own velocity: the damping of that
  discrete machine acts on a velocity ``dt/2 qdd`` late, which a continuous-time fit reads as an
  inertia ``damping x dt/2`` lower. A property of the integrator, not of a machine.
- ``substeps`` > 1: close to continuous time, as a real machine behaves: MuJoCo's RK4 at
  ``timestep / substeps``, the controller (a drive whose torque loop is much faster than its
  published samples) updated every physics step, and one sample published per model timestep
  holding the state and the torque at that instant.
"""
from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

from ...errors import CablelabError
from .mjcf import dof_joints, names


@dataclass(frozen=True)
class Hidden:
    """What the truth has and the user's model lacks.

    Args:
        payload: ``(body, mass kg, (x, y, z) m in the body frame)`` added as a point-mass child
            body, or None.
        damping, frictionloss, armature: per joint name: viscous friction (N m s/rad), Coulomb
            friction (N m), reflected inertia (kg m^2).
        gain: per joint: the effort sensor reads gain x the applied force.
        stiffness: per joint ``(k, q0)``: a spring pulling the joint towards q0.
        link_mass: per body: mass added at its centre of mass (kg; its inertia unchanged).
        tendon_stiffness: per tendon: the cable stretches with stiffness k (N/m): its winch
            encoder reads the rest length paid out, MuJoCo's tendon length minus the stretch
            T / k under MuJoCo's own tension T (recorded lengths only, :func:`record_all`).
        length_offset: per tendon: the zero of its length encoder (m).
    """

    payload: tuple | None = None
    damping: dict = field(default_factory=dict)
    frictionloss: dict = field(default_factory=dict)
    armature: dict = field(default_factory=dict)
    gain: dict = field(default_factory=dict)
    stiffness: dict = field(default_factory=dict)
    link_mass: dict = field(default_factory=dict)
    tendon_stiffness: dict = field(default_factory=dict)
    length_offset: dict = field(default_factory=dict)


def _set(joint, attr: str, value: float) -> None:
    """Set a joint attribute that is a number or (newer MuJoCo) a coefficient vector whose
    first entry is the linear coefficient."""
    old = getattr(joint, attr)
    if np.ndim(old):
        new = np.zeros_like(old)
        new[0] = value
        setattr(joint, attr, new)
    else:
        setattr(joint, attr, float(value))


def truth_model(xml: str, hidden: Hidden = Hidden(), timestep: float | None = None, *,
                euler: bool = True, substeps: int = 1):
    """The truth :class:`mujoco.MjModel`: ``xml`` edited with MjSpec to hold ``hidden``;
    ``euler``: explicit Euler without implicit damping (else the model's own integrator);
    ``substeps`` > 1: RK4 at 1/substeps of the (model's or given) timestep instead, close to
    continuous time (:func:`simulate` publishes one sample per ``substeps`` physics steps)."""
    import mujoco

    spec = mujoco.MjSpec.from_string(xml)
    if substeps > 1:
        spec.option.integrator = mujoco.mjtIntegrator.mjINT_RK4
    elif euler:
        spec.option.integrator = mujoco.mjtIntegrator.mjINT_EULER
        spec.option.disableflags |= int(mujoco.mjtDisableBit.mjDSBL_EULERDAMP)
    if timestep or substeps > 1:
        spec.option.timestep = float(timestep or spec.option.timestep) / max(1, int(substeps))
    if hidden.payload is not None:
        body, mass, pos = hidden.payload
        b = spec.body(body).add_body(name="hidden_payload", pos=list(pos))
        b.ipos = [0.0, 0.0, 0.0]
        b.mass = float(mass)
        b.inertia = [1e-9, 1e-9, 1e-9]
        b.explicitinertial = True
    for b, dm in hidden.link_mass.items():
        spec.body(b).mass = spec.body(b).mass + float(dm)
    for attr in ("damping", "frictionloss", "armature"):
        for j, v in getattr(hidden, attr).items():
            _set(spec.joint(j), attr, v)
    for j, (k, q0) in hidden.stiffness.items():
        _set(spec.joint(j), "stiffness", k)
        hinge = spec.joint(j).type == mujoco.mjtJoint.mjJNT_HINGE
        # MJCF angles are in degrees unless the model's compiler says radians
        spec.joint(j).springref = float(np.degrees(q0) if hinge and spec.compiler.degree else q0)
    return spec.compile()


def excitation(duration: float, dt: float, n: int, seed: int = 0, amplitude: float = 0.8,
               band_hz: tuple[float, float] = (0.15, 1.2), harmonics: int = 5):
    """Multisine reference per joint: positions, velocities, accelerations (T, n)."""
    rng = np.random.default_rng(seed)
    t = np.arange(int(round(duration / dt))) * dt
    f = rng.uniform(*band_hz, size=(harmonics, n))
    ph = rng.uniform(0, 2 * np.pi, size=(harmonics, n))
    a = amplitude / harmonics / (1 + f)
    w = 2 * np.pi * f
    arg = w[None] * t[:, None, None] + ph[None]
    q = np.sum(a * (np.sin(arg) - np.sin(ph)), axis=1)
    qd = np.sum(a * w * np.cos(arg), axis=1)
    qdd = np.sum(-a * w**2 * np.sin(arg), axis=1)
    return t, q, qd, qdd


def actuator_moments(model, data) -> np.ndarray:
    """(nu, nv) dense actuator moment matrix (generalised force per unit actuator force)."""
    import mujoco

    out = np.zeros((model.nu, model.nv))
    mujoco.mju_sparse2dense(out, data.actuator_moment, data.moment_rownnz, data.moment_rowadr,
                            data.moment_colind)
    return out


def simulate(model, duration: float = 12.0, seed: int = 0, kp: float = 400.0, kd: float = 40.0,
             amplitude: float = 0.8, pretension: float = 30.0, lengths: bool = False,
             substeps: int = 1):
    """Run the truth model under PD + bias feedback tracking a multisine.

    The wanted generalised force is spread over the actuators by least squares around a
    pretension of ``pretension`` N on every tendon actuator (cables must pull), exactly on the
    joints an actuator drives (joint actuators: the force itself). With ``substeps`` 1, one
    sample per physics step (:func:`mujoco.mj_step1` / ``mj_step2``: the control computed between
    them); else the controller acts every physics step and one sample is kept per ``substeps``
    steps (:func:`_simulate_substeps`).

    Returns:
        ``t (T,), q (T, nv), qd (T, nv), effort (T, nv), act (T, nu)``: the state each step
        starts from, the generalised actuator force applied during it (``qfrc_actuator``) and
        the actuator forces; with ``lengths``, also the tendon lengths (T, ntendon) m.
    """
    import mujoco

    if substeps > 1:
        return _simulate_substeps(model, duration, seed, kp, kd, amplitude, pretension, lengths,
                                  int(substeps))
    d = mujoco.MjData(model)
    dt = model.opt.timestep
    t, qr, qdr, _ = excitation(duration, dt, model.nv, seed, amplitude)
    T = len(t)
    q, qd, eff, act, ten_len = _buffers(model, T)
    mujoco.mj_forward(model, d)
    kp_v, kd_v, c0 = _drive(model, kp, kd, pretension)
    for k in range(T):
        mujoco.mj_step1(model, d)
        tau = kp_v * (qr[k] - d.qpos[: model.nv]) + kd_v * (qdr[k] - d.qvel) + d.qfrc_bias
        A = actuator_moments(model, d).T                     # (nv, nu)
        d.ctrl[:] = c0 + np.linalg.lstsq(A, tau - A @ c0, rcond=None)[0]
        q[k], qd[k] = d.qpos[: model.nv], d.qvel
        ten_len[k] = d.ten_length
        mujoco.mj_step2(model, d)
        eff[k] = d.qfrc_actuator
        act[k] = d.actuator_force
    return (t, q, qd, eff, act, ten_len) if lengths else (t, q, qd, eff, act)


def _buffers(model, T: int) -> tuple:
    """Empty (T, .) arrays of a record: q, qd, joint effort (nv each), actuator force (nu),
    tendon length (ntendon)."""
    return (np.empty((T, model.nv)), np.empty((T, model.nv)), np.empty((T, model.nv)),
            np.empty((T, model.nu)), np.empty((T, model.ntendon)))


def _drive(model, kp: float, kd: float, pretension: float) -> tuple:
    """The recording drive's PD gains per dof (scaled by the dof's own inertia ``dof_M0``) and
    the controls that hold every tendon actuator at ``pretension`` N (zero for the others)."""
    import mujoco

    mass = np.maximum(np.array(model.dof_M0), 0.05)
    tendon = model.actuator_trntype == int(mujoco.mjtTrn.mjTRN_TENDON)
    c0 = np.where(tendon, -pretension / np.maximum(np.abs(model.actuator_gear[:, 0]), 1e-12), 0.0)
    return kp * mass, kd * mass, c0


def _simulate_substeps(model, duration, seed, kp, kd, amplitude, pretension, lengths, substeps):
    """:func:`simulate` close to continuous time: ``mj_step`` (any integrator, RK4 included,
    which the split step does not support) with the controller updated before every physics
    step, one sample kept every ``substeps`` steps: the state at that instant and the torque
    there. The drive's torque steps at each physics step, so at a step's instant it is the mean
    of the torque held over the step before and the one after (the torque held from the instant
    on would lead the motion by half a physics step, which a fit reads as damping)."""
    import mujoco

    d = mujoco.MjData(model)
    dt = model.opt.timestep
    t_all, qr, qdr, _ = excitation(duration, dt, model.nv, seed, amplitude)
    T = len(t_all) // substeps
    q, qd, eff, act, ten_len = _buffers(model, T)
    mujoco.mj_forward(model, d)
    kp_v, kd_v, c0 = _drive(model, kp, kd, pretension)
    before = None                                            # (qfrc_actuator, actuator_force)
    for i in range(T * substeps):
        mujoco.mj_forward(model, d)
        tau = kp_v * (qr[i] - d.qpos[: model.nv]) + kd_v * (qdr[i] - d.qvel) + d.qfrc_bias
        A = actuator_moments(model, d).T                     # (nv, nu)
        d.ctrl[:] = c0 + np.linalg.lstsq(A, tau - A @ c0, rcond=None)[0]
        mujoco.mj_fwdActuation(model, d)                    # the forces of the new controls
        after = (d.qfrc_actuator.copy(), d.actuator_force.copy())
        if i % substeps == 0:
            k = i // substeps
            q[k], qd[k], ten_len[k] = d.qpos[: model.nv], d.qvel, d.ten_length
            b = after if before is None else before
            eff[k], act[k] = 0.5 * (b[0] + after[0]), 0.5 * (b[1] + after[1])
        before = after
        mujoco.mj_step(model, d)
    t = t_all[: T * substeps: substeps]
    return (t, q, qd, eff, act, ten_len) if lengths else (t, q, qd, eff, act)


def record(model, hidden: Hidden = Hidden(), *, duration: float = 12.0, seed: int = 0,
           encoder_bits: int = 18, effort_noise: float = 0.02, effort_quantum: float = 1e-3,
           substeps: int = 1):
    """A simulated record as a sensor sees it: positions quantised to ``2 pi / 2^bits``, efforts
    times the hidden gain plus white noise (N m) and quantised; NaN for a joint no actuator
    drives. Returns ``(t, q, effort, joint names)``; :func:`record_all` also the tensions."""
    r = record_all(model, hidden, duration=duration, seed=seed, encoder_bits=encoder_bits,
                   effort_noise=effort_noise, effort_quantum=effort_quantum, substeps=substeps)
    return r["t"], r["q"], r["effort"], r["joints"]


def record_all(model, hidden: Hidden = Hidden(), *, duration: float = 12.0, seed: int = 0,
               encoder_bits: int = 18, effort_noise: float = 0.02, effort_quantum: float = 1e-3,
               tension_noise: float = 0.2, length_quantum: float = 1e-5, substeps: int = 1) -> dict:
    """:func:`record` plus ``tension`` (T, n_tendons): per tendon the pull of the actuators on
    it (N) with white noise ``tension_noise``, ``length`` (T, n_tendons): the length its winch
    encoder reads (m, quantised to ``length_quantum``: MuJoCo's tendon length, less the stretch
    of a ``hidden.tendon_stiffness`` cable under its true tension, plus the encoder's zero), and
    ``tendons`` their names. ``substeps``: physics steps per sample (:func:`simulate`; the
    model's timestep is the physics step, :func:`truth_model` divides it)."""
    t, q, qd, eff, act, ten_len = simulate(model, duration, seed, lengths=True, substeps=substeps)
    rng = np.random.default_rng(seed + 1)
    quantum = 2 * np.pi / 2**encoder_bits
    q_meas = np.round(q / quantum) * quantum
    joints = dof_joints(model)
    gain = np.array([hidden.gain.get(j, 1.0) for j in joints])
    e = eff * gain + rng.normal(0.0, effort_noise, eff.shape)
    e = np.round(e / effort_quantum) * effort_quantum
    driven = np.zeros(model.nv, bool)
    on_joint = model.actuator_trntype == 0
    driven[model.jnt_dofadr[model.actuator_trnid[on_joint, 0]]] = True
    e[:, ~driven] = np.nan                 # a joint without actuator has no effort sensor
    tension = np.zeros((len(t), model.ntendon))
    for a in np.flatnonzero(model.actuator_trntype == 3):                 # mjTRN_TENDON
        tension[:, model.actuator_trnid[a, 0]] -= act[:, a] * model.actuator_gear[a, 0]
    tn = names(model, "tendon")
    k = np.array([hidden.tendon_stiffness.get(x, np.inf) for x in tn])
    zero = np.array([hidden.length_offset.get(x, 0.0) for x in tn])
    length = ten_len - tension / k + zero           # tension before the sensor noise: the truth
    length = np.round(length / length_quantum) * length_quantum
    tension += rng.normal(0.0, tension_noise, tension.shape)
    return {"t": t, "q": q_meas, "effort": e, "joints": joints, "tension": tension,
            "length": length, "tendons": tn}


def description_yaml(xml: str, **section) -> str:
    """A description (YAML text) of an mjcf machine with the model inline."""
    from ...description import dump_description, load_description

    import yaml

    text = yaml.safe_dump({"plant": "mjcf", "gravity": 9.81, "mjcf": {"model": xml, **section}},
                          sort_keys=False)
    return dump_description(load_description(text))


def write_bag(path, xml: str, hidden: Hidden = Hidden(), *, duration: float = 12.0, seed: int = 0,
              overwrite: bool = True, cable_lengths: bool = False, substeps: int = 1,
              **section) -> str:
    """Simulate the truth (``xml`` + ``hidden``) and write a contract bag of it: the description
    (the user's model, without the hidden effect), ``/mjcf/joint_states`` and, for the section's
    ``tendons``, ``/mjcf/cable_tensions`` (with the winch encoders' lengths as ``position`` when
    ``cable_lengths``). ``substeps`` > 1: recorded close to continuous time (RK4 at
    1/substeps of the model's timestep, one sample per model timestep; see the module)."""
    from ...bags import BagWriter

    model = truth_model(xml, hidden, substeps=substeps)
    r = record_all(model, hidden, duration=duration, seed=seed, substeps=substeps)
    desc = description_yaml(xml, **section)
    t0 = 1000.0
    with BagWriter(path, overwrite=overwrite) as w:
        w.write_description(desc, t=t0)
        w.write_joint_states("/mjcf/joint_states", t0 + r["t"], r["joints"], position=r["q"],
                             effort=r["effort"])
        measured = list(section.get("tendons") or ())
        if measured:
            idx = [r["tendons"].index(x) for x in measured]
            w.write_joint_states("/mjcf/cable_tensions", t0 + r["t"], measured,
                                 position=r["length"][:, idx] if cable_lengths else None,
                                 effort=r["tension"][:, idx])
    return str(path)


__all__ = ["Hidden", "MjcfSim", "actuator_moments", "description_yaml", "excitation", "record",
           "record_all", "simulate", "truth_model", "write_bag"]


class MjcfSim:
    """A running simulation of an ``mjcf:`` section's model at its own timestep:
    ``advance(ctrl, duration)`` holds the actuator controls for whole physics steps.

    Args:
        section: the parsed ``mjcf:`` section; gravity: g along -z, m/s^2.
        hidden: what the simulated truth has beyond the section's model (:class:`Hidden`).
    """

    def __init__(self, section, gravity: float = 9.81, hidden: Hidden | None = None):
        import mujoco

        if hidden is None:
            self.model = section.compiled(gravity)
        else:
            self.model = truth_model(section.model, hidden, euler=False)
            self.model.opt.gravity[:] = (0.0, 0.0, -float(gravity))
        self.data = mujoco.MjData(self.model)
        self.joints = dof_joints(self.model)
        self.tendons = list(section.tendons)
        tn = names(self.model, "tendon")
        m = self.model
        # tension of each measured tendon = its actuators' pull: (n_tendons, nu) @ actuator_force
        self._pull = np.array([np.where((m.actuator_trntype == 3) & (m.actuator_trnid[:, 0] == tn.index(x)),
                                        -m.actuator_gear[:, 0], 0.0) for x in self.tendons],
                              float).reshape(len(self.tendons), m.nu)             # mjTRN_TENDON
        self._step, self._dt, self._nv = mujoco.mj_step, float(m.opt.timestep), m.nv
        self._on_joint = m.actuator_trntype == 0                             # mjTRN_JOINT
        # (nv, nu) generalised force of the joint actuators per unit actuator force: the gear at
        # the joint's dof for hinge and slide joints (mjJNT_HINGE 3, SLIDE 2), else per step
        self._joint_moment = np.zeros((m.nv, m.nu))
        for a in np.flatnonzero(self._on_joint):
            j = m.actuator_trnid[a, 0]
            if m.jnt_type[j] not in (2, 3):
                self._joint_moment = None
                break
            self._joint_moment[m.jnt_dofadr[j], a] = m.actuator_gear[a, 0]
        mujoco.mj_forward(self.model, self.data)

    @property
    def t(self) -> float:
        return float(self.data.time)

    def advance(self, ctrl, duration: float) -> None:
        """Hold ``ctrl`` (nu,) for ``duration`` s (at least one step)."""
        self.data.ctrl[:] = ctrl
        n = max(1, int(round(duration / self._dt)))
        if n == 1:
            self._step(self.model, self.data)
        else:
            self._step(self.model, self.data, nstep=n)

    def state(self):
        """``(t, q (nv,), qd (nv,), effort (nv,), tension (n_tendons,))``: ``effort`` is the
        generalised force of the joint actuators (what a joint's own motor current measures; the
        tendon actuators' pull reaches the joints through the measured tensions, so it is not
        counted twice); the tension of a measured tendon is the pull of the actuators on it (N,
        >= 0 when pulling)."""
        d = self.data
        if self._joint_moment is not None:          # hinge and slide joints: constant moments
            effort = self._joint_moment @ d.actuator_force
        else:
            effort = actuator_moments(self.model, d)[self._on_joint].T @ d.actuator_force[self._on_joint]
        return (d.time, d.qpos[: self._nv].copy(), d.qvel.copy(), effort,
                self._pull @ d.actuator_force)


def default_description() -> str:
    """The shipped example (the three-joint arm, payload on ``tool``) as a description: what the
    simulator node runs when given none."""
    from .examples import ARM3

    return description_yaml(ARM3.read_text(encoding="utf-8"), payload_body="tool")


def hidden_payload(section, mass: float) -> Hidden | None:
    """The truth's payload of ``mass`` kg on ``section.payload_body`` at that body's centre of
    mass (None for no mass).

    Raises:
        CablelabError: a mass but no ``payload_body`` in the section.
    """
    if not mass > 0:
        return None
    if not section.payload_body:
        raise CablelabError("cable_sim_node --plant mjcf: payload_mass needs mjcf.payload_body in "
                            "the description")
    model = section.compiled()
    com = model.body_ipos[names(model, "body").index(section.payload_body)]
    return Hidden(payload=(section.payload_body, float(mass), tuple(map(float, com))))


def publish_period(timestep: float, rate: float) -> float:
    """The simulator's publishing period: whole physics steps of ``timestep`` s nearest to
    ``1 / rate`` (at least one; ``rate`` NaN: every step)."""
    return timestep * max(1, round(1.0 / (rate * timestep))) if rate == rate else timestep
