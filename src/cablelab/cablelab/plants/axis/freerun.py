"""Free-run simulation of the axis (MuJoCo, window by window): the ``compare`` free-run check and
the simulation-based fit (``identify --simulation``)."""
from __future__ import annotations

import numpy as np

from ...errors import CablelabError
from ...fit.simulation import fit_free_run_windows, free_run_windows, window_length, window_starts
from ...dataset import Dataset

#: free-run horizon: the record is cut into windows of this length, each simulated from the
#: measured state at its start (a marginally stable axis drifts over a long open-loop run)
FREE_RUN_HORIZON_S = 0.5


def free_run(ds: Dataset, param_sets: list[dict], horizon_s: float = FREE_RUN_HORIZON_S) -> np.ndarray:
    """Simulate the axis (MuJoCo) driven by the measured effort, window by window.

    Each window of ``horizon_s`` starts at the measured (filtered) q, qd and is driven by the
    measured effort minus the sensor offset ``OF`` (zero-order hold at the sample period), with
    M, Fv, Fc (and mc for a revolute joint) from each parameter set. All windows and parameter
    sets run in one :func:`mujoco.rollout.rollout` batch.

    Args:
        ds: axis dataset; param_sets: list of ``{"M", "Fv", "Fc", "OF", "mc"}`` (missing = 0).
    Returns:
        (k, N, 1) simulated positions (NaN in the tail that does not fill a window).
    """
    import dataclasses

    import mujoco
    import mujoco.rollout

    from .mjcf import build_mjcf
    from .sim import AxisTruth
    from .truth import initial_state

    dt = ds.dt
    w, n_win = free_run_windows(ds, horizon_s)
    q, qd = ds.signals["q"], ds.signals["qd"]
    starts = np.arange(n_win) * w
    desc = ds.description
    models, x0s, ctrls = [], [], []
    for ps in param_sets:
        mc = float(ps.get("mc", 0.0))
        d2 = desc
        if desc.axis.joint_type == "revolute":
            d2 = desc.with_section("axis", dataclasses.replace(desc.axis, gravity_moment=max(mc, 0.0)))
        truth = AxisTruth(inertia=max(float(ps.get("M", 0.0)), 1e-9),
                          viscous=max(float(ps.get("Fv", 0.0)), 0.0),
                          coulomb=max(float(ps.get("Fc", 0.0)), 0.0), timestep=dt)
        m = build_mjcf(d2, truth)
        u = ds.y[:, 0] - float(ps.get("OF", 0.0))
        for s in starts:
            models.append(m)
            x0s.append(initial_state(m, q[s], qd[s]))
            ctrls.append(u[s:s + w])
    data = [mujoco.MjData(models[0]) for _ in range(2)]
    # sensors are evaluated before each step's integration: sensor row j is sample s + j
    _, sens = mujoco.rollout.rollout(models, data, np.array(x0s), np.array(ctrls)[:, :, None])
    out = np.full((len(param_sets), ds.n, 1), np.nan)
    out[:, : n_win * w, 0] = sens[:, :, 0].reshape(len(param_sets), n_win * w)
    return out


def free_run_compare(ds: Dataset, params: dict, horizon_s: float = FREE_RUN_HORIZON_S) -> dict:
    """Free-run position error of identified parameters: NRMSE of the position deviation from
    each window's start (the motion the model must reproduce) and max abs error."""
    sim = free_run(ds, [params], horizon_s)[0, :, 0]
    q = ds.signals["q"]
    ok = np.isfinite(sim)
    base = window_starts(q, window_length(ds.dt, horizon_s))
    dq_meas, dq_sim = (q - base)[ok], (sim - base)[ok]
    e = dq_sim - dq_meas
    return {"channel": "position", "horizon_s": horizon_s,
            "nrmse": float(np.sqrt(np.mean(e**2)) / np.sqrt(np.mean(dq_meas**2))),
            "max_abs": float(np.max(np.abs(e))), "pearson": float(np.corrcoef(dq_meas, dq_sim)[0, 1])}


def fit_free_run(ds: Dataset, start: dict, *, objective: str = "nmse",
                 free: tuple[str, ...] = ("M", "Fv", "Fc"), horizon_s: float = FREE_RUN_HORIZON_S,
                 max_iter: int = 30, progress: bool = False):
    """Simulation-based identification of the axis: free-run windows (:func:`free_run`) matched to
    the measured motion with :func:`~cablelab.fit.simulation.fit_simulation` (NMSE of 003 eq. 28
    or Pearson of 000 eq. 3-7). The output is the position deviation from each window's start.

    Args:
        start: start values by name (e.g. the inverse-model LS result); parameters not in
            ``free`` are held at their start value.
        free: parameters to fit, bounded to [start / 5, start * 5]; those the model does not have
            (absent from ``start``) are left out (held at 0).
    Raises:
        CablelabError: a parameter of the model whose inverse-model value is not positive (a
            negative inertia or friction cannot start a physical simulation), or none to fit.
    """
    from ...effects.base import Param

    params = []
    names = {"M": "inertia", "Fv": "viscous friction", "Fc": "Coulomb friction"}
    for k in free:
        if k not in start:
            continue          # not in the model (e.g. Fc without joint_coulomb_friction)
        v = float(start[k])
        if not v > 0:
            raise CablelabError(
                f"free-run fit: the inverse-model fit gives {names.get(k, k)} {k} = {v:.4g}, not "
                f"physical (a simulation needs {k} > 0); the model does not explain this record "
                f"(check the effort's sign and units, or fix it: --fix {k}=VALUE)")
        params.append(Param(k, "", v, v / 5.0, v * 5.0))
    if not params:
        raise CablelabError(f"free-run fit: the model has none of {', '.join(free)} to fit")
    return fit_free_run_windows(lambda sets: free_run(ds, sets, horizon_s), ds.signals["q"], start,
                                params, horizon_s, ds.dt, objective=objective, max_iter=max_iter,
                                progress=progress)
