"""The same parameters fitted the other way: :mod:`mujoco.sysid` over rollouts of a bag.

``cablelab identify --plant mjcf`` fits joint friction, armature and a payload by one linear least
squares on MuJoCo's inverse dynamics (equation error). This module fits them as
:mod:`mujoco.sysid` does (simulation error): the record is cut into short windows, each rolled out
from its measured initial state under the measured joint efforts as controls, and Gauss-Newton
(:func:`mujoco.sysid.optimize`, finite-difference Jacobians) moves the parameters until the
rolled-out joint positions match the measured ones; :func:`mujoco.sysid.calculate_intervals`
gives 95 % intervals. It is the independent oracle of the linear fit (and its speed yardstick:
``bench/bench_mjcf_sysid.py``).

The record must be of joint-driven motors (control = joint effort, gear 1, as the shipped arm).
"""
from __future__ import annotations

import contextlib
import io
import time
from dataclasses import dataclass

import numpy as np

#: the effect ids fitted here and how they map onto the model
EFFECTS = ("joint_viscous_friction", "joint_armature", "payload_mass")


@dataclass(frozen=True)
class RolloutFit:
    """Fitted values and 95 % half-widths by cablelab's parameter names (``Fv[j]``,
    ``armature[j]``, ``m``, ``com_x``..), the wall time (s), optimiser evaluations, windows.

    ``ci95`` is :func:`mujoco.sysid.calculate_intervals`' (white residual assumed);
    ``ci95_inflated`` the same widened by ``sqrt((1 + r1) / (1 - r1))`` for the lag-1
    autocorrelation r1 of the rollout residual, the rule cablelab's own simulation fit applies
    (:mod:`cablelab.fit.simulation`): a rollout's position error drifts, far from white."""

    values: dict
    ci95: dict
    ci95_inflated: dict
    seconds: float
    evaluations: int
    windows: int


def _set_coef(obj, attr: str, value: float) -> None:
    old = getattr(obj, attr)
    if np.ndim(old):                     # newer MuJoCo: a coefficient vector, linear term first
        new = np.zeros_like(old)
        new[0] = value
        setattr(obj, attr, new)
    else:
        setattr(obj, attr, float(value))


def initial_velocity(q: np.ndarray, dt: float, window: int = 41) -> np.ndarray:
    """Joint velocities to start each rollout from: a Savitzky-Golay derivative of the measured
    positions (the encoder quantum divided by dt would be a velocity error of several mrad/s),
    less half a step of acceleration: MuJoCo's Euler step ``q[k] - q[k-1] = dt qd[k]`` makes the
    state's velocity the backward difference, which the smooth derivative at ``k`` overshoots by
    ``dt/2 qdd``."""
    from scipy.signal import savgol_filter

    v = savgol_filter(q, window, 4, deriv=1, delta=dt, axis=0)
    a = savgol_filter(q, window, 4, deriv=2, delta=dt, axis=0)
    return v - 0.5 * dt * a


def sysid_fit(xml: str, t, q, effort, joints, *, payload_body: str | None = None,
              window: float = 0.5, effects=EFFECTS, euler: bool = True,
              max_iters: int = 50) -> RolloutFit:
    """Fit ``effects`` with :mod:`mujoco.sysid` to a record of the model ``xml``.

    Args:
        xml: the user's model (MJCF); t (N,) s, q (N, nv) measured positions, effort (N, nv) the
            joint efforts (controls of gear-1 joint motors), in ``joints`` order.
        payload_body: the body carrying the unknown payload (a point mass at a fitted position in
            its frame), needed for ``payload_mass``.
        window: seconds per rollout window (each starts from the measured state).
        euler: roll out with explicit Euler (the integrator the record was made with), else the
            model's own.
    """
    import mujoco
    from mujoco import sysid

    from ...fit.identification import lag1_autocorrelation

    t = np.asarray(t, float) - float(t[0])
    q, effort = np.asarray(q, float), np.asarray(effort, float)
    spec = mujoco.MjSpec.from_string(xml)
    if euler:
        spec.option.integrator = mujoco.mjtIntegrator.mjINT_EULER
        spec.option.disableflags |= int(mujoco.mjtDisableBit.mjDSBL_EULERDAMP)
    for j in joints:
        s = spec.add_sensor()
        s.name, s.type = f"{j}_pos", mujoco.mjtSensor.mjSENS_JOINTPOS
        s.objtype, s.objname = mujoco.mjtObj.mjOBJ_JOINT, j
    params = sysid.ParameterDict()
    names: list[str] = []
    if "joint_viscous_friction" in effects:
        for j in joints:
            params.add(sysid.Parameter(f"Fv[{j}]", 0.1, 0.0, 10.0, modifier=lambda s, p, j=j:
                                       _set_coef(s.joint(j), "damping", p.value[0])))
            names.append(f"Fv[{j}]")
    if "joint_armature" in effects:
        for j in joints:
            params.add(sysid.Parameter(f"armature[{j}]", 0.01, 0.0, 1.0, modifier=lambda s, p, j=j:
                                       _set_coef(s.joint(j), "armature", p.value[0])))
            names.append(f"armature[{j}]")
    if "payload_mass" in effects:
        if not payload_body:
            raise ValueError("payload_mass needs payload_body")
        c0 = np.array(spec.body(payload_body).ipos, float)
        c0 = np.where(np.isfinite(c0), c0, 0.0)
        b = spec.body(payload_body).add_body(name="sysid_payload", pos=list(c0))
        b.ipos = [0.0, 0.0, 0.0]         # unset (NaN) would put the inertial at the body's pos again
        b.mass, b.inertia, b.explicitinertial = 0.5, [1e-9] * 3, True
        params.add(sysid.Parameter("m", 0.5, 0.0, 20.0, modifier=lambda s, p:
                                   setattr(s.body("sysid_payload"), "mass", p.value[0])))
        params.add(sysid.Parameter("com", c0, c0 - 0.5, c0 + 0.5, modifier=lambda s, p:
                                   setattr(s.body("sysid_payload"), "pos", p.value)))
        names += ["m", "com_x", "com_y", "com_z"]
    start = time.perf_counter()
    model0 = spec.compile()
    dt = float(model0.opt.timestep)
    if abs(float(np.median(np.diff(t))) - dt) > 1e-3 * dt:
        raise ValueError(f"the record is sampled every {np.median(np.diff(t)):g} s, the model steps "
                         f"{dt:g} s: rollouts pair one sample with one step")
    qd = initial_velocity(q, dt)
    n = max(2, int(round(window / dt)))
    inits, ctrls, sens = [], [], []
    for k in range(25, len(t) - n - 25, n):      # away from the ends of the derivative filter
        s0 = sysid.create_initial_state(model0, q[k], qd[k])
        s0[0] = t[k]
        inits.append(s0)
        ctrls.append(sysid.TimeSeries(t[k:k + n], effort[k:k + n]))
        # step i's position sensor holds the state the step starts from, q[k + i]; sysid drops
        # the first measured row and pairs the rest with the n - 1 steps
        sens.append(sysid.TimeSeries.from_names(t[k:k + n], q[k - 1:k + n - 1], model0))
    seqs = sysid.ModelSequences("record", spec, [f"w{i}" for i in range(len(inits))], inits,
                                ctrls, sens)
    # the samples are the model's steps already: no resampling (resampling a window whose stamps
    # span 249.0000001 steps stretches it to 251 samples and shifts the controls by up to a step)
    residual_fn = sysid.build_residual_fn(models_sequences=[seqs], resample_true=False)
    evals = [0]

    def counted(x, p, **kw):
        evals[0] += 1
        return residual_fn(x, p, **kw)

    with contextlib.redirect_stdout(io.StringIO()):      # the optimiser's per-iteration lines
        opt, res = sysid.optimize(params, counted, optimizer="mujoco", verbose=False,
                                  max_iters=max_iters)
    r, _, _ = residual_fn(opt.as_vector(), opt)
    _, ci = sysid.calculate_intervals(r, res.jac)
    ns = len(joints)
    r1 = float(np.mean([lag1_autocorrelation(np.asarray(w).reshape(-1, ns)) for w in r]))
    inflation = float(np.sqrt((1.0 + r1) / (1.0 - r1)))
    seconds = time.perf_counter() - start
    x = opt.as_vector()
    return RolloutFit(values=dict(zip(names, map(float, x))), ci95=dict(zip(names, map(float, ci))),
                      ci95_inflated={k: float(c) * inflation for k, c in zip(names, ci)},
                      seconds=seconds, evaluations=evals[0], windows=len(inits))
