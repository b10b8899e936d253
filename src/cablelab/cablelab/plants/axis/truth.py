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

from .sim import AxisTruth, axis_mjcf


@dataclass(frozen=True)
class AxisRun:
    """t (N,) s, q (N,) measured position, effort (N,) measured effort, effort_true (N,) the
    actuator force without offset, delay or noise."""

    t: np.ndarray
    q: np.ndarray
    effort: np.ndarray
    effort_true: np.ndarray


def build_axis_model(description, truth: AxisTruth, servo: tuple[float, float] | None = None):
    """Compiled MuJoCo axis (:func:`~cablelab.plants.axis.sim.axis_mjcf`) for synthetic data and
    simulation-based fits, with sensors ``[q, actuator force]``.

    Integration is explicit semi-implicit Euler with Euler damping off, so the force a sensor reports
    is the force applied over the step (implicit integrators fold dt * (damping + servo kv) into
    the inertia; RK4 re-evaluates a servo inside the step; both bias the "true" M and Fv by a few %
    against u = M qdd + ...). The friction-loss constraint is stiff (Fc sign(qd) down to ~1e-4 m/s
    instead of the default soft ramp that looks like extra viscous friction near reversals).

    Args:
        servo: ``(kp, kv)``: the actuator is a position servo whose control is the reference
            position; None: a force/torque motor whose control is the effort.
    """
    import mujoco

    ax = description.axis
    spec = mujoco.MjSpec.from_string(axis_mjcf(ax.joint_type, truth, ax.gravity_moment,
                                               description.gravity))
    spec.option.integrator = mujoco.mjtIntegrator.mjINT_EULER
    spec.option.disableflags |= mujoco.mjtDisableBit.mjDSBL_EULERDAMP
    joint = spec.joints[0]
    joint.solref_friction[:] = [2 * truth.timestep, 1.0]
    joint.solimp_friction[:3] = [0.99, 0.99, 0.001]
    if servo is not None:
        kp, kv = servo
        act = spec.actuators[0]
        act.gaintype = mujoco.mjtGain.mjGAIN_FIXED
        act.gainprm[0] = kp
        act.biastype = mujoco.mjtBias.mjBIAS_AFFINE
        act.biasprm[0:3] = [0.0, -kp, -kv]
    spec.add_sensor(type=mujoco.mjtSensor.mjSENS_JOINTPOS, objtype=mujoco.mjtObj.mjOBJ_JOINT,
                    objname="joint")
    spec.add_sensor(type=mujoco.mjtSensor.mjSENS_ACTUATORFRC, objtype=mujoco.mjtObj.mjOBJ_ACTUATOR,
                    objname="drive")
    return spec.compile()


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
                  noise_position: float = 0.0, delay: float = 0.0, seed: int = 0) -> AxisRun:
    """Simulate the axis under a position servo and return what a sensor would record.

    Args:
        description: plant description (axis section: joint type, gravity moment).
        truth: inertia, viscous, Coulomb, offset, physics timestep.
        duration: s; fs: recorded sample rate, Hz (a divisor of the physics rate).
        amplitude: reference amplitude (m or rad); bandwidth_hz: servo bandwidth.
        noise_effort, noise_position: white-noise standard deviations.
        delay: the reported effort lags the actuator force by this time, s.
    """
    import mujoco
    import mujoco.rollout

    w = 2 * np.pi * bandwidth_hz
    model = build_axis_model(description, truth,
                             servo=(truth.inertia * w * w, 2 * 0.8 * truth.inertia * w))
    data = mujoco.MjData(model)
    dt = model.opt.timestep
    step = max(1, int(round(1.0 / (fs * dt))))
    n_phys = int(round(duration / dt))
    t_phys = np.arange(n_phys) * dt  # sensor row j = state before step j, at time j dt
    ref = reference(t_phys, amplitude)
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
