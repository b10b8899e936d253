"""The axis dataset (CONTRACT sections 2-3, ``/axis/joint_states``): bag -> Dataset.

Inverse model (EMPS reference, IDIM):

    force = M qdd + Fv qd + Fc sign(qd) + OF  (+ m c g sin q for a revolute joint, q = 0 down)

one output channel (the measured motor force / torque), one actuator (identity map).
"""
from __future__ import annotations

import numpy as np

from ...conditioning import condition_motion
from ...errors import CablelabError
from ...dataset import Dataset
from ...plant_interface import DatasetOptions

from .topics import JOINT_STATE, JOINT_STATES as TOPIC


def dataset_from_arrays(t, q, effort, description, options: DatasetOptions | None = None, *, qd=None,
                        source: str = "data") -> Dataset:
    """Axis dataset from raw arrays.

    Args:
        t: (N,) s; q: (N,) position (m or rad); effort: (N,) force (N) or torque (N m);
        description: :class:`~cablelab.description.Description` with an ``axis`` section.
        options: the conditioning (defaults when None).
        qd: optional measured velocity (N,); derived from q when None or not finite.
    """
    opts = (options or DatasetOptions()).conditioning
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


def dataset(bag, description, options: DatasetOptions) -> Dataset:
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
    distrusted = js.names[col] in options.derived_velocity.get(TOPIC, ())
    return dataset_from_arrays(js.t, q, eff, description, options,
                               qd=qd if np.isfinite(qd).all() and not distrusted else None,
                               source=str(bag.path))
