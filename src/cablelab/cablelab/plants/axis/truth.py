"""Synthetic axis measurements with known hidden effects (ground truth for the workbench tests
and benchmarks).

The axis of :mod:`cablelab.plants.axis.sim` (MuJoCo: inertia, joint damping = viscous friction,
``frictionloss`` = Coulomb friction, gravity load for a revolute joint) tracks a smooth multi-sine
reference with MuJoCo's own position servo; the whole run is one :func:`mujoco.rollout.rollout`
call (no Python loop over samples). The reported effort is the actuator force, plus a sensor
offset, delayed by ``delay`` and with white noise: the hidden effects a diagnosis must find.
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from .mjcf import build_mjcf
from .sim import AxisTruth


@dataclass(frozen=True)
class AxisRun:
    """t (N,) s, q (N,) measured position, effort (N,) measured effort, effort_true (N,) the
    actuator force without offset, delay or noise."""

    t: np.ndarray
    q: np.ndarray
    effort: np.ndarray
    effort_true: np.ndarray


def initial_state(model, q0: float, qd0: float = 0.0) -> np.ndarray:
    """Full physics state vector of the axis at (q0, qd0)."""
    import mujoco

    data = mujoco.MjData(model)
    data.qpos[0], data.qvel[0] = q0, qd0
    mujoco.mj_forward(model, data)
    x0 = np.empty(mujoco.mj_stateSize(model, mujoco.mjtState.mjSTATE_FULLPHYSICS))
    mujoco.mj_getState(model, data, x0, mujoco.mjtState.mjSTATE_FULLPHYSICS)
    return x0


def reference(t: np.ndarray, amplitude: float, base_hz: float = 0.25) -> np.ndarray:
    """Smooth multi-sine reference with many velocity reversals (m or rad)."""
    w = 2 * np.pi * base_hz
    return amplitude * (0.6 * np.sin(w * t) + 0.3 * np.sin(2.7 * w * t + 0.4)
                        + 0.15 * np.sin(6.1 * w * t + 1.3))


def simulate_axis(description, truth: AxisTruth, *, duration: float = 20.0, fs: float = 500.0,
                  amplitude: float = 0.2, bandwidth_hz: float = 4.0, noise_effort: float = 0.0,
                  noise_position: float = 0.0, delay: float = 0.0, seed: int = 0,
                  reference_fn=None) -> AxisRun:
    """Simulate the axis under a position servo and return what a sensor would record.

    Args:
        description: plant description (axis section: joint type, gravity moment).
        truth: inertia, viscous, Coulomb, offset, physics timestep.
        duration: s; fs: recorded sample rate, Hz (a divisor of the physics rate).
        amplitude: reference amplitude (m or rad); bandwidth_hz: servo bandwidth.
        noise_effort, noise_position: white-noise standard deviations.
        delay: the reported effort lags the actuator force by this time, s.
        reference_fn: ``fn(t) -> q`` (or a tuple whose first item is q) the servo tracks instead
            of the multi-sine (e.g. a designed excitation, :func:`cablelab.excite.read_reference`).
    """
    import mujoco
    import mujoco.rollout

    w = 2 * np.pi * bandwidth_hz
    model = build_mjcf(description, truth,
                             servo=(truth.inertia * w * w, 2 * 0.8 * truth.inertia * w))
    data = mujoco.MjData(model)
    dt = model.opt.timestep
    step = max(1, int(round(1.0 / (fs * dt))))
    n_phys = int(round(duration / dt))
    t_phys = np.arange(n_phys) * dt  # sensor row j = state before step j, at time j dt
    if reference_fn is None:
        ref = reference(t_phys, amplitude)
    else:
        ref = reference_fn(t_phys)
        ref = np.asarray(ref[0] if isinstance(ref, tuple) else ref, float).reshape(-1)
    x0 = initial_state(model, ref[0])
    _, sens = mujoco.rollout.rollout(model, data, x0[None], ref[None, :, None])
    sens = sens[0]
    t = t_phys[::step]
    q = sens[::step, 0]
    force = sens[::step, 1]
    rng = np.random.default_rng(seed)
    meas = np.interp(t - delay, t, force, left=force[0]) + truth.offset
    meas = meas + noise_effort * rng.normal(size=t.size)
    q_meas = q + noise_position * rng.normal(size=t.size)
    return AxisRun(t=t, q=q_meas, effort=meas, effort_true=force)
