"""MuJoCo plant of the hopping leg with event-located phase switches and impact maps (spec 003
sec. 4).

Model: one body ``body`` (mass m) on a slide joint ``hop`` along +z, gravity -g z, one ``motor``
actuator on ``hop`` (ctrl = F_in, N). No contact model: 003's impact map (eq. 24) is an abrupt
velocity change, applied explicitly. Each control period (ZOH input, like the 1 kHz hardware loop):

1. the phase force (spring + stance damping, or flight damping; :mod:`.hybrid`) is written to
   ``qfrc_applied`` (variant (a) of the spec; integrator Euler, because ``qfrc_applied`` would be
   frozen across RK4 stages);
2. ``mj_step``; then the phase guard is evaluated. If it changed sign, the pre-step state is
   restored, MuJoCo steps by the fraction ``a = g0 / (g0 - g1)`` of dt, the velocity map is
   applied, the phase switches and the remaining ``(1 - a) dt`` is stepped in the new phase.

:class:`LegSim` is the stepper (used by the simulator node and the controller's model), and
:func:`simulate` runs it under a torque law and returns a :class:`Trajectory` with the measured
signals (003 sec. 3.1: 0.09 mm encoder, backward-difference velocity, contact switch) next to
the truth.
"""
from __future__ import annotations

import math
from dataclasses import dataclass, field
from typing import Callable

import mujoco
import numpy as np

from . import topics
from .hybrid import (FLIGHT, LIFTOFF, STANCE, TOUCHDOWN, LegParams, flight_accel, grf, input_force,
                     stance_accel,
                     liftoff_guard, liftoff_map, spring_force, touchdown_map)
from .mjcf import build_mjcf

__all__ = ["LegSim", "Trajectory", "Event", "simulate", "open_loop", "measure", "quantise", "motor_angle"]

DT = 1e-3  #: control / sample period of 003 sec. 3.1, s


@dataclass(frozen=True)
class Event:
    """A phase transition: time (s), kind (touchdown / liftoff), height (m), velocity before and
    after the map (m/s)."""

    t: float
    kind: str
    z: float
    zd_minus: float
    zd_plus: float


class LegSim:
    """Hybrid hopper stepped at the control period with located events (spec 003 sec. 4).

    Args:
        params: model parameters. z, zd: initial state (m, m/s). phase: initial phase (default:
            stance when z < z_td). dt: control period, s.
    """

    def __init__(self, params: LegParams, z: float, zd: float = 0.0, phase: int | None = None,
                 dt: float = DT):
        self.p = params
        self.dt = dt
        self.model = build_mjcf(params, dt)
        self.data = mujoco.MjData(self.model)
        self._q, self._v = self.data.qpos, self.data.qvel  # cached views (hot loop)
        self.reset(z, zd, phase)

    def reset(self, z: float, zd: float = 0.0, phase: int | None = None) -> None:
        """Restart from (z, zd) at t = 0 with the same parameters (reuses the model and data)."""
        params, dt = self.p, self.dt
        mujoco.mj_resetData(self.model, self.data)
        self.phase = (STANCE if z < params.z_td else FLIGHT) if phase is None else phase
        self._q[0] = z
        # MuJoCo's semi-implicit Euler is a leapfrog whose velocity lives half a step after the
        # position it moves; starting it from zdot(t0 - dt/2) makes the positions second order
        # (removes the g t dt / 2 free-fall lag of a start from zdot(t0))
        a0 = stance_accel(z, zd, 0.0, params) if self.phase == STANCE else flight_accel(zd, params)
        self._v[0] = zd - 0.5 * dt * a0
        # leg length frozen in flight (E1); a flight started below z_td lifted off there or lower
        self.l_fl = min(params.z_td, float(z))
        self.t_d = 0.0  # last touch-down time (eq. 26)
        self.events: list[Event] = []
        self.f_in = 0.0
        self._fresh_stance = False  # lift-off guard skipped in the first sample of stance

    # -------------------------------------------------------------- state
    @property
    def t(self) -> float:
        return float(self.data.time)

    @property
    def z(self) -> float:
        return float(self.data.qpos[0])

    @property
    def zd(self) -> float:
        return float(self.data.qvel[0])

    # -------------------------------------------------------------- internals
    def _phase_force(self, z: float, zd: float) -> float:
        p = self.p
        if self.phase == STANCE:
            return spring_force(z, p) - p.d_s * zd - (p.Fc * ((zd > 0) - (zd < 0)) if p.Fc else 0.0) \
                + (p.m - p.flight_mass) * p.g   # MuJoCo's weight is m g; the leg's is m_f g
        # flight: MuJoCo applies -m g with the stance mass m; this force gives the zdd of eq. 23
        return p.m * (flight_accel(zd, p) + p.g)

    def _guard(self, z: float, zd: float) -> float:
        if self.phase == STANCE:
            return liftoff_guard(z, zd, self.f_in, self.p)
        return z - self.l_fl

    def _advance(self, h: float) -> None:
        d = self.data
        d.ctrl[0] = self.f_in if self.phase == STANCE else 0.0
        d.qfrc_applied[0] = self._phase_force(self._q[0], self._v[0])
        if h == self.dt:
            mujoco.mj_step(self.model, d)
        else:
            self.model.opt.timestep = h
            mujoco.mj_step(self.model, d)
            self.model.opt.timestep = self.dt

    def _switch(self) -> None:
        d, p = self.data, self.p
        z, zm = float(d.qpos[0]), float(d.qvel[0])
        if self.phase == FLIGHT:
            zp = touchdown_map(zm, p)
            self.phase, self.t_d, self._fresh_stance = STANCE, float(d.time), True
            kind = TOUCHDOWN
        else:
            zp, self.l_fl = liftoff_map(z, zm, p)
            self.phase, kind = FLIGHT, LIFTOFF
        d.qvel[0] = zp
        self.events.append(Event(float(d.time), kind, z, zm, zp))

    # -------------------------------------------------------------- public
    def step(self, tau: float) -> None:
        """Advance one control period with motor torque ``tau`` (N m, ZOH)."""
        d, q, v, p = self.data, self._q, self._v, self.p
        z0, zd0, t0 = float(q[0]), float(v[0]), float(d.time)
        stance = self.phase == STANCE
        if stance:
            f_in = self.f_in = input_force(tau, z0, p)
            base = spring_force(z0, p) - p.d_s * zd0          # F_GRF - F_in (eq. 25)
            g0 = min((f_in + base) / p.k, p.z_td - z0)        # lift-off guard
            if g0 < 0.0 and not self._fresh_stance:
                # the new ZOH input sample itself drives F_GRF below 0: lift off at the sample
                self._switch()
                stance, zd0 = False, float(v[0])
        if stance:
            d.ctrl[0] = f_in
            d.qfrc_applied[0] = base - (p.Fc * ((zd0 > 0) - (zd0 < 0)) if p.Fc else 0.0) \
                + (p.m - p.flight_mass) * p.g   # weight m_f g, not MuJoCo's m g
        else:
            self.f_in = 0.0
            g0 = z0 - self.l_fl                               # touch-down guard
            d.ctrl[0] = 0.0
            d.qfrc_applied[0] = p.m * (flight_accel(zd0, p) + p.g)
        mujoco.mj_step(self.model, d)
        if stance and self._fresh_stance:  # lift-off guard not armed in the first stance sample
            self._fresh_stance = False
            return
        g1 = self._guard(float(q[0]), float(v[0]))
        if g0 >= 0.0 and g1 < 0.0:
            a = g0 / (g0 - g1)
            q[0], v[0], d.time = z0, zd0, t0
            if a > 0:
                self._advance(a * self.dt)
            self._switch()
            self.f_in = 0.0  # a new stance's torque starts at the next sample (ZOH)
            rest = (1.0 - a) * self.dt
            if rest > 1e-12:
                self._advance(rest)
            d.time = t0 + self.dt

    def grf(self) -> float:
        """Ground reaction force of the current state (eq. 25), N; 0 in flight."""
        if self.phase != STANCE:
            return 0.0
        return float(grf(self.z, self.zd, self.f_in, self.p))


# ----------------------------------------------------------------------------- batch simulation

@dataclass
class Trajectory:
    """Samples at the control period (index n = state at t[n], tau[n] applied over [t_n, t_n+1)).

    Truth: z, zd (m, m/s), phase (0/1), grf (N). Inputs: tau (N m), f_in (N). Measured: z_meas
    (quantised), zd_meas (backward difference), contact (switch, 0/1). Events: located transitions.
    """

    t: np.ndarray
    z: np.ndarray
    zd: np.ndarray
    phase: np.ndarray
    tau: np.ndarray
    f_in: np.ndarray
    grf: np.ndarray
    events: list = field(default_factory=list)
    z_meas: np.ndarray | None = None
    zd_meas: np.ndarray | None = None
    contact: np.ndarray | None = None

    def event_times(self, kind: str | None = None) -> np.ndarray:
        return np.array([e.t for e in self.events if kind is None or e.kind == kind])


TorqueLaw = Callable[[float, "LegSim"], float]


def open_loop(T: float, P: float) -> TorqueLaw:
    """003 eq. 26 as a torque law of the stepper (restarted at each located touch-down)."""
    w = 2.0 * math.pi / P

    def law(t: float, sim: LegSim) -> float:
        return T * math.sin(w * (t - sim.t_d)) if sim.phase == STANCE else 0.0
    return law


def simulate(params: LegParams, z0: float, zd0: float, duration: float, torque: TorqueLaw | None = None,
             *, dt: float = DT, phase: int | None = None, resolution: float = 9e-5,
             contact_delay: float = 0.0, seed: int | None = 0) -> Trajectory:
    """Run the hybrid MuJoCo plant for ``duration`` s under ``torque(t, sim)`` (default 0) and
    return the truth and the measured signals (:func:`measure`)."""
    sim = LegSim(params, z0, zd0, phase, dt)
    n = int(round(duration / dt)) + 1
    law = torque or (lambda t, s: 0.0)
    d, q, v = sim.data, sim._q, sim._v
    rows = []
    for i in range(n):
        t = float(d.time)
        stance = sim.phase == STANCE
        tau = law(t, sim) if stance else 0.0
        z = float(q[0])
        rows.append((t, z, float(v[0]), sim.phase, tau, input_force(tau, z, params) if stance else 0.0))
        if i < n - 1:
            sim.step(tau)
    out = np.array(rows).T
    t, z, zd, ph, tau, f_in = out
    g = np.where(ph == STANCE, grf(z, zd, f_in, params), 0.0)
    traj = Trajectory(t, z, zd, ph.astype(int), tau, f_in, g, list(sim.events))
    measure(traj, resolution=resolution, contact_delay=contact_delay, seed=seed)
    return traj


def quantise(z, resolution: float, offset: float = 0.0):
    """Encoder reading of height ``z`` (m): rounded to ``resolution`` (0: exact) about a zero
    offset ``offset``; scalar or array."""
    if resolution <= 0:
        return z
    if type(z) is float:        # one sample (the live loops): round() rounds half to even as np.round
        return round((z + offset) / resolution) * resolution - offset
    return np.round((np.asarray(z) + offset) / resolution) * resolution - offset


def motor_angle(z, L: float):
    """Motor angle theta (rad) at body height ``z`` (m) of the symmetric two-link leg of link
    length ``L`` (z = 2 L cos theta); scalar or array."""
    return np.arccos(np.clip(np.asarray(z) / (2.0 * L), -1.0, 1.0))


def measure(traj: Trajectory, *, resolution: float = 9e-5, contact_delay: float = 0.0,
            seed: int | None = 0) -> Trajectory:
    """Hardware measurement model (003 sec. 3.1): z quantised to the encoder resolution (with a
    random encoder zero offset when ``seed`` is given), zdot = backward difference of the quantised
    z, contact switch = stance flag delayed by ``contact_delay`` s."""
    off = 0.0 if seed is None else float(np.random.default_rng(seed).uniform(0, resolution))
    zq = quantise(traj.z, resolution, off) if resolution > 0 else traj.z.copy()
    zdq = np.empty_like(zq)
    zdq[1:] = np.diff(zq) / np.diff(traj.t)
    zdq[0] = zdq[1] if len(zq) > 1 else 0.0
    contact = traj.phase.astype(float)
    if contact_delay > 0:
        shift = int(round(contact_delay / float(np.median(np.diff(traj.t)))))
        contact = np.concatenate([np.full(shift, contact[0]), contact[:-shift]]) if shift else contact
    traj.z_meas, traj.zd_meas, traj.contact = zq, zdq, contact
    return traj


def write_bag(path, traj: Trajectory, description_yaml: str, *, contact: bool = True,
              overwrite: bool = False) -> None:
    """Write a simulated run as a contract bag (spec sec. 5 ``/leg/*`` topics, /clock,
    /plant_description): measured height (encoder) and velocity, motor torque, the contact switch
    (unless ``contact=False``: a bag without one) and the simulation truth."""
    from ...bags import BagWriter

    with BagWriter(path, overwrite=overwrite) as w:
        w.write_description(description_yaml)
        w.write_clock(traj.t)
        n = len(traj.t)
        theta = motor_angle(traj.z_meas, 0.15)
        w.write_joint_states(topics.JOINT_STATES, traj.t, ("body", "motor"),
                             position=np.c_[traj.z_meas, theta], velocity=np.c_[traj.zd_meas, np.zeros(n)],
                             effort=np.c_[traj.f_in, traj.tau])
        if contact:
            w.write_joint_states(topics.CONTACT, traj.t, ("contact",), position=traj.contact[:, None])
        w.write_float_arrays(topics.EFFORT_COMMANDS, traj.t, traj.tau[:, None])
        w.write_joint_states(topics.GROUND_TRUTH, traj.t, ("height", "phase", "grf"),
                             position=np.c_[traj.z, traj.phase, np.zeros(n)],
                             velocity=np.c_[traj.zd, np.zeros(n), np.zeros(n)],
                             effort=np.c_[np.zeros(n), np.zeros(n), traj.grf])
