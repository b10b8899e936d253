"""The single-axis plant (CONTRACT sections 2-3, ``/axis/joint_states``).

Inverse model (EMPS reference, IDIM):

    force = M qdd + Fv qd + Fc sign(qd) + OF  (+ m c g sin q for a revolute joint, q = 0 down)

one output channel (the measured motor force / torque), one actuator (identity map). The nominal
model is inertia + viscous friction (+ gravity when the description gives ``gravity_moment``);
Coulomb friction, sensor offset and time delay are the candidates a diagnosis tries.
"""
from __future__ import annotations

import numpy as np

from ...conditioning import Conditioning, condition_motion
from ...errors import CablelabError
from ...fit.simulation import fit_free_run_windows, free_run_windows, window_length, window_starts
from ...dataset import Dataset
from ...registry import Plant, register_plant
from .description import parse_section

TOPIC = "/axis/joint_states"
JOINT_STATE = "sensor_msgs/msg/JointState"


def dataset_from_arrays(t, q, effort, description, options: dict | None = None, *, qd=None,
                        source: str = "data") -> Dataset:
    """Axis dataset from raw arrays.

    Args:
        t: (N,) s; q: (N,) position (m or rad); effort: (N,) force (N) or torque (N m);
        description: :class:`~cablelab.description.Description` with an ``axis`` section.
        options: ``{"conditioning": Conditioning}`` (defaults when absent).
        qd: optional measured velocity (N,); derived from q when None or not finite.
    """
    options = options or {}
    opts = options.get("conditioning") or Conditioning()
    revolute = description.axis is not None and description.axis.joint_type == "revolute"
    c = condition_motion(np.asarray(t, float), np.asarray(q, float), np.asarray(effort, float), opts,
                         revolute=revolute, qd=None if qd is None else np.asarray(qd, float),
                         source=source)
    unit = "N m" if revolute else "N"
    qd_c = c["qd"].reshape(-1)
    qd_s = c["qd_smooth"].reshape(-1)
    ds = Dataset(
        plant="axis", t=c["t"], y=c["effort"].reshape(-1, 1), channels=("joint",), units=(unit,),
        signals={"q": c["q"].reshape(-1), "qd": qd_c, "qdd": c["qdd"].reshape(-1),
                 "cutoff_hz": c["cutoff_hz"], "rest_velocity": qd_s[:, None],
                 "load_warnings": c["warnings"]},
        actuators=("joint",), act_vel=qd_c[:, None], act_units=((unit, "rad" if revolute else "m"),),
        inputs={"velocity": qd_s, "acceleration": c["qdd_smooth"].reshape(-1)},
        regimes={"position": _position_bins(c["q"].reshape(-1))},
        description=description, source=source,
    )
    if c["parallel_hz"]:
        from ...parallel_filter import edge_mask

        ds = ds.replace(parallel_hz=c["parallel_hz"], valid=ds.valid & edge_mask(ds.t, c["parallel_hz"]))
    # drives that stop: the zero-speed zone is not fitted (cablelab.velocity, issue 10)
    from ...velocity import exclude_zero_speed, position_quantum, speed_resolution

    res = 0.0 if qd is not None else speed_resolution(position_quantum(q), c["cutoff_hz"])
    return exclude_zero_speed(ds, floor=res)


def _position_bins(q: np.ndarray, bins: int = 4) -> np.ndarray:
    edges = np.quantile(q, np.linspace(0, 1, bins + 1)[1:-1])
    idx = np.searchsorted(edges, q)
    lo = np.concatenate([[q.min()], edges])
    hi = np.concatenate([edges, [q.max()]])
    labels = np.array([f"q in [{a:.3g}, {b:.3g}]" for a, b in zip(lo, hi)])
    return labels[idx]


def dataset(bag, description, options: dict | None = None) -> Dataset:
    """Axis dataset from a bag's ``/axis/joint_states`` (joint ``joint`` or the only joint)."""
    bag.require(TOPIC, JOINT_STATE)
    js = bag.joint_state(TOPIC)
    if not js.names:
        raise CablelabError(f"{bag.path}: {TOPIC} has no joint names")
    col = js.names.index("joint") if "joint" in js.names else 0
    if len(js.names) > 1 and "joint" not in js.names:
        raise CablelabError(f"{bag.path}: {TOPIC} has joints {js.names}; expected one named 'joint'")
    q, eff = js.position[:, col], js.effort[:, col]
    for name, arr in (("position", q), ("effort", eff)):
        if not np.isfinite(arr).any():
            raise CablelabError(f"{bag.path}: {TOPIC} has no {name} values")
    qd = js.velocity[:, col]
    # a measured velocity that contradicts the position (bagcheck) is not used: derived instead
    distrusted = js.names[col] in ((options or {}).get("derived_velocity") or {}).get(TOPIC, ())
    return dataset_from_arrays(js.t, q, eff, description, options,
                               qd=qd if np.isfinite(qd).all() and not distrusted else None,
                               source=str(bag.path))


def baseline(description) -> tuple[str, ...]:
    """Nominal model: inertia + viscous friction (+ gravity for a revolute load with a known
    gravity moment)."""
    base = ("axis_inertia", "joint_viscous_friction")
    ax = description.axis if description is not None else None
    if ax is not None and ax.joint_type == "revolute" and ax.gravity_moment:
        base += ("axis_gravity",)
    return base


def candidates(description) -> tuple[str, ...]:
    """Effects a diagnosis tries on the axis."""
    cands = ("axis_inertia", "joint_viscous_friction", "joint_coulomb_friction",
             "torque_sensor_offset", "time_delay")
    ax = description.axis if description is not None else None
    if ax is not None and ax.joint_type == "revolute":
        cands += ("axis_gravity",)
    return cands


# ----------------------------------------------------------------------------- free-run simulation

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

    from .sim import AxisTruth
    from .truth import build_axis_model, initial_state

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
        m = build_axis_model(d2, truth)
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


AXIS = register_plant(Plant(
    name="axis",
    topics=((TOPIC, JOINT_STATE),),
    dataset=dataset,
    baseline=baseline,
    candidates=candidates,
    channels_doc="joint: measured motor force (N, prismatic) or torque (N m, revolute)",
    simulate=free_run_compare,
    simulation_fit=fit_free_run,
    section=parse_section,
    contract_topics={
        TOPIC: JOINT_STATE,
        "/axis/reference": "trajectory_msgs/msg/JointTrajectory",
        # additions (docs/nodes.md): command input, live parameter estimate, simulation truth
        "/axis/effort_command": "std_msgs/msg/Float64MultiArray",
        "/axis/parameter_estimate": "std_msgs/msg/Float64MultiArray",
        "/axis/ground_truth/joint_states": JOINT_STATE,
    },
    joint_topic=TOPIC,
    joints=("joint",),
    capabilities=frozenset({"joint_actuators"}),
    channels=("joint",),
    topic_names=lambda desc: {TOPIC: ["joint"], "/axis/ground_truth/joint_states": ["joint"]},
))
