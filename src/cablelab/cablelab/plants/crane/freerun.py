"""Free-run comparison of an identified crane model (002 sec. 6.1: the same inputs to the model
and to the crane, compare the motion).

The record is cut into windows of ``horizon_s``; each window starts from the measured state
(q, qd incl. the swing) and is driven by the measured efforts (minus an identified sensor
offset, zero-order hold at the sample period) in a MuJoCo crane built from the identified
parameters (masses, inertias, counterbalance, base tilt, joint friction). All windows run in one
:func:`mujoco.rollout.rollout` batch. The crane is under-actuated and marginally stable, so
windows are short (default 1 s).
"""
from __future__ import annotations

import numpy as np

from ...errors import CablelabError
from ...fit.simulation import fit_free_run_windows, free_run_windows, window_length, window_starts
from ...dataset import Dataset
from .kinematics import gimbal_rates_to_swing, swing_to_gimbal
from .model import JOINTS, CraneParams

__all__ = ["FREE_RUN_HORIZON_S", "truth_from_params", "free_run", "free_run_compare", "fit_free_run"]

FREE_RUN_HORIZON_S = 1.0
#: shorter windows for the simulation-based fit: the open-loop crane is so sensitive to its
#: parameters (+-5 % of m_b already swings the payload wildly within 1 s) that long windows leave
#: no slope for the optimiser away from the optimum
FIT_HORIZON_S = 0.4
_COORDS = ("alpha", "beta", "d", "theta1", "theta2")


def truth_from_params(params: dict, description) -> "object":
    """A :class:`cablelab.plants.crane.sim.CraneTruth` from identified workbench parameters by name
    (``I_tot, I_b, m, m_b, m_c, l_c, tilt_x, tilt_y, Fv[...], Fc[...]``; missing = description
    or 0)."""
    from .sim import CraneTruth

    base = CraneParams.from_description(description)
    pos = lambda k, default: max(float(params.get(k, default)), 0.0)
    p = CraneParams(boom_length=base.boom_length, payload_mass=max(pos("m", base.payload_mass), 1e-6),
                    boom_mass=pos("m_b", base.boom_mass),
                    counterbalance_mass=pos("m_c", 0.0), counterbalance_distance=pos("l_c", 0.0),
                    slew_inertia=max(pos("I_tot", 0.0), 1e-6), luff_inertia=pos("I_b", 0.0),
                    gravity=base.gravity)
    if p.boom_mass + p.counterbalance_mass <= 0:
        p = p.replace(boom_mass=1e-6)
    # base_tilt: tilt_y = g_x / g = sin(ey), tilt_x = -g_y / g = cos(ey) sin(ex) (sim.gravity_in_base)
    ey = float(np.arcsin(np.clip(float(params.get("tilt_y", 0.0)), -0.5, 0.5)))
    ex = float(np.arcsin(np.clip(float(params.get("tilt_x", 0.0)) / np.cos(ey), -0.5, 0.5)))
    visc = tuple(pos(f"Fv[{j}]", 0.0) for j in JOINTS)
    coul = tuple(pos(f"Fc[{j}]", 0.0) for j in JOINTS)
    return CraneTruth(params=p, base_tilt=(ex, ey), viscous=visc, coulomb=coul, timestep=1e-3)


def _mujoco_state(q: np.ndarray, qd: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """MuJoCo qpos, qvel (N, 5) from contract q, qd (N, 5): inverts the gimbal rate map."""
    psi, phi = swing_to_gimbal(q[:, 1], q[:, 3], q[:, 4])
    qpos = np.stack([q[:, 0], q[:, 1], psi, phi, q[:, 2]], axis=1)
    z = np.zeros(q.shape[0])
    one = np.ones(q.shape[0])
    # columns of d(theta1, theta2)/d(gamma, phi), gamma = beta + psi (linear in the rates)
    c_g = np.stack(gimbal_rates_to_swing(q[:, 1], psi, phi, one, z, z), axis=1)
    c_p = np.stack(gimbal_rates_to_swing(q[:, 1], psi, phi, z, z, one), axis=1)
    J = np.stack([c_g, c_p], axis=2)                                   # (N, 2, 2)
    gd_pd = np.linalg.solve(J, qd[:, 3:5, None])[:, :, 0]
    qvel = np.stack([qd[:, 0], qd[:, 1], gd_pd[:, 0] - qd[:, 1], gd_pd[:, 1], qd[:, 2]], axis=1)
    return qpos, qvel


def free_run(ds: Dataset, params, horizon_s: float = FREE_RUN_HORIZON_S) -> np.ndarray:
    """Simulated contract coordinates, window by window (NaN in the unfilled tail).

    Args:
        params: one parameter dict, or a list of them (one batch: one model per set).
    Returns:
        (N, 5) for one dict, (k, N, 5) for a list of k dicts.
    """
    import mujoco
    import mujoco.rollout

    from .mjcf import build_mjcf
    from .sim import qpos_to_contract

    sets = [params] if isinstance(params, dict) else list(params)
    dt = ds.dt
    w, n_win = free_run_windows(ds, horizon_s)
    q, qd = ds.signals["q"], ds.signals["qd"]
    starts = np.arange(n_win) * w
    qpos, qvel = _mujoco_state(q[starts], qd[starts])
    steps = max(1, int(round(dt / 1e-3)))
    models, x0s, ctrls = [], [], []
    for ps in sets:
        truth = truth_from_params(ps, ds.description)
        truth = truth.__class__(**{**truth.__dict__, "timestep": dt / steps})
        model = build_mjcf(truth)
        data = mujoco.MjData(model)
        spec = mujoco.mjtState.mjSTATE_FULLPHYSICS
        x0 = np.zeros((n_win, mujoco.mj_stateSize(model, spec)))
        for k in range(n_win):  # a handful of windows: set each initial state
            data.qpos[:], data.qvel[:] = qpos[k], qvel[k]
            mujoco.mj_getState(model, data, x0[k], spec)
        offset = np.array([float(ps.get(f"OF[{j}]", 0.0)) for j in JOINTS])
        u = ds.y - offset
        ctrl = np.repeat(u[: n_win * w].reshape(n_win, w, 3), steps, axis=1)
        models += [model] * n_win
        x0s.append(x0)
        ctrls.append(ctrl)
    data = [mujoco.MjData(models[0]) for _ in range(2)]
    state, _ = mujoco.rollout.rollout(models, data, np.concatenate(x0s), np.concatenate(ctrls))
    nq = models[0].nq
    st = state[:, steps - 1::steps, :]                                 # after each sample period
    qstart = np.tile(qpos, (len(sets), 1))
    qp = np.concatenate([qstart[:, None, :], st[:, :-1, 1:1 + nq]], axis=1)
    out = np.full((len(sets), ds.n, 5), np.nan)
    out[:, : n_win * w] = qpos_to_contract(qp.reshape(-1, nq)).reshape(len(sets), n_win * w, 5)
    return out[0] if isinstance(params, dict) else out


def free_run_compare(ds: Dataset, params: dict, horizon_s: float = FREE_RUN_HORIZON_S) -> dict:
    """Free-run error per coordinate: NRMSE of the deviation from each window's start."""
    sim = free_run(ds, params, horizon_s)
    q = ds.signals["q"]
    ok = np.isfinite(sim).all(axis=1)
    base = window_starts(q, window_length(ds.dt, horizon_s))
    out = {"horizon_s": horizon_s, "channels": {}}
    for j, name in enumerate(_COORDS):
        dm, dsim = (q[:, j] - base[:, j])[ok], (sim[:, j] - base[:, j])[ok]
        e = dsim - dm
        den = np.sqrt(np.mean(dm ** 2))
        out["channels"][name] = {"nrmse": float(np.sqrt(np.mean(e ** 2)) / den) if den > 0 else None,
                                 "max_abs": float(np.max(np.abs(e)))}
    vals = [c["nrmse"] for c in out["channels"].values() if c["nrmse"] is not None]
    out["channel"] = "q = alpha, beta, d, theta1, theta2 (mean NRMSE)"
    out["nrmse"] = float(np.mean(vals))
    out["max_abs"] = float(max(c["max_abs"] for c in out["channels"].values()))  # rad or m
    return out


def fit_free_run(ds: Dataset, start: dict, *, objective: str = "nmse",
                 free: tuple[str, ...] = ("I_tot", "I_b", "m", "m_b", "m_c"),
                 horizon_s: float = FIT_HORIZON_S, max_iter: int = 20, progress: bool = False):
    """Simulation-based identification of the crane: free-run windows (:func:`free_run`) matched
    to the measured motion (deviation of alpha, beta, d, theta1, theta2 from each window's start)
    with :func:`~cablelab.fit.simulation.fit_simulation` (NMSE of 003 eq. 28 or Pearson of 000
    eq. 3-7). Parameters of ``free`` with a positive start value are fitted within
    [start / 5, start * 5]; the others are held at their start value.
    """
    from ...effects.base import Param

    params = [Param(k, "", float(start[k]), float(start[k]) / 5.0, float(start[k]) * 5.0)
              for k in free if float(start.get(k, 0.0)) > 0]
    if not params:
        raise CablelabError("free-run fit: no free parameter with a positive start value")
    return fit_free_run_windows(lambda sets: free_run(ds, sets, horizon_s), ds.signals["q"], start,
                                params, horizon_s, ds.dt, objective=objective, max_iter=max_iter,
                                progress=progress)
