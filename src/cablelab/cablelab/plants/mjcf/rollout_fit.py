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
    ``ci95_windows`` the cluster-robust (sandwich) intervals with each window a cluster
    (:func:`window_robust_ci`): a rollout's position error drifts, far from white, most of all
    under the noise of the measured efforts that drive it, and windows are independent."""

    values: dict
    ci95: dict
    ci95_windows: dict
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


def initial_velocity(q: np.ndarray, dt: float, window: int = 41, euler: bool = False) -> np.ndarray:
    """Joint velocities to start each rollout from: a Savitzky-Golay derivative of the measured
    positions (the encoder quantum divided by dt would be a velocity error of several mrad/s).
    ``euler``: less half a step of acceleration: MuJoCo's Euler step ``q[k] - q[k-1] = dt qd[k]``
    makes the state's velocity the backward difference, which the smooth derivative at ``k``
    overshoots by ``dt/2 qdd``."""
    from scipy.signal import savgol_filter

    v = savgol_filter(q, window, 4, deriv=1, delta=dt, axis=0)
    if not euler:
        return v
    a = savgol_filter(q, window, 4, deriv=2, delta=dt, axis=0)
    return v - 0.5 * dt * a


def step_controls(effort: np.ndarray, euler: bool) -> np.ndarray:
    """The control held over each rollout step from the sampled efforts (N, nu): for a machine
    recorded in continuous time (``euler`` False) the mean of the effort over the step,
    ``(e[k] + e[k+1]) / 2`` (holding ``e[k]`` would delay the torque by half a step, which the fit
    reads as an inertia ``damping x dt/2`` low); ``euler``: the record is MuJoCo's own Euler step,
    whose control was ``e[k]`` held over step k."""
    e = np.asarray(effort, float)
    if euler:
        return e
    return np.concatenate([0.5 * (e[:-1] + e[1:]), e[-1:]])


def window_robust_ci(residuals, jac: np.ndarray, z: float = 1.96) -> np.ndarray:
    """95 % half-widths of a least-squares fit over independent windows whose residuals are
    correlated within each: the sandwich ``H^-1 (sum_w g_w g_w^T) H^-1`` with ``H = J^T J`` and
    ``g_w = J_w^T r_w`` the gradient of window w (rows of ``jac`` in the order of
    ``residuals``), times W / (W - 1) for the W windows."""
    rs = [np.ravel(np.asarray(w, float)) for w in residuals]
    edges = np.cumsum([0] + [len(w) for w in rs])
    J = np.asarray(jac, float)
    if edges[-1] != J.shape[0]:
        raise ValueError(f"{J.shape[0]} Jacobian rows for {edges[-1]} residuals")
    g = np.stack([J[a:b].T @ w for a, b, w in zip(edges[:-1], edges[1:], rs)])
    h_inv = np.linalg.pinv(J.T @ J)
    cov = h_inv @ (g.T @ g) @ h_inv * len(rs) / max(len(rs) - 1, 1)
    return z * np.sqrt(np.maximum(np.diag(cov), 0.0))


def sysid_fit(xml: str, t, q, effort, joints, *, payload_body: str | None = None,
              window: float = 0.25, effects=EFFECTS, integrator: str = "rk4",
              max_iters: int = 50) -> RolloutFit:
    """Fit ``effects`` with :mod:`mujoco.sysid` to a record of the model ``xml``.

    Args:
        xml: the user's model (MJCF); t (N,) s, q (N, nv) measured positions, effort (N, nv) the
            joint efforts (controls of gear-1 joint motors), in ``joints`` order.
        payload_body: the body carrying the unknown payload (a point mass at a fitted position in
            its frame), needed for ``payload_mass``.
        window: seconds per rollout window (each starts from the measured state).
        integrator: ``"rk4"``: the record is a machine in continuous time (a real one, or
            :func:`.sim.write_bag` with ``substeps``), rolled out with RK4 at the model's
            timestep; ``"euler"``: the record was made with MuJoCo's explicit Euler one sample
            per step (implicit damping off) and is rolled out the same way.

    The measured efforts drive the rollouts, so their sensor noise moves the simulated
    positions by its double integral over each window, an error that grows with the window and
    that only the window-clustered intervals (``ci95_windows``) hold.
    """
    if integrator not in ("rk4", "euler"):
        raise ValueError(f"integrator {integrator!r}: rk4 or euler")
    euler = integrator == "euler"
    import mujoco
    from mujoco import sysid

    t = np.asarray(t, float) - float(t[0])
    q, effort = np.asarray(q, float), np.asarray(effort, float)
    spec = mujoco.MjSpec.from_string(xml)
    if euler:
        spec.option.integrator = mujoco.mjtIntegrator.mjINT_EULER
        spec.option.disableflags |= int(mujoco.mjtDisableBit.mjDSBL_EULERDAMP)
    else:
        spec.option.integrator = mujoco.mjtIntegrator.mjINT_RK4
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
    qd = initial_velocity(q, dt, euler=euler)
    u = step_controls(effort, euler)
    n = max(2, int(round(window / dt)))
    inits, ctrls, sens = [], [], []
    for k in range(25, len(t) - n - 25, n):      # away from the ends of the derivative filter
        s0 = sysid.create_initial_state(model0, q[k], qd[k])
        s0[0] = t[k]
        inits.append(s0)
        ctrls.append(sysid.TimeSeries(t[k:k + n], u[k:k + n]))
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
    ci_w = window_robust_ci(r, res.jac)
    seconds = time.perf_counter() - start
    x = opt.as_vector()
    return RolloutFit(values=dict(zip(names, map(float, x))), ci95=dict(zip(names, map(float, ci))),
                      ci95_windows=dict(zip(names, map(float, ci_w))),
                      seconds=seconds, evaluations=evals[0], windows=len(inits))
