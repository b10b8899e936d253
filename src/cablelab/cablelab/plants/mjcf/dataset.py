"""Bag -> :class:`~cablelab.dataset.Dataset` for the ``mjcf`` plant.

Channels: one generalised force per hinge / slide joint of the model, in dof order. The measured
side ``y`` is the joint effort of ``joint_states`` (a joint without actuator and without effort:
0, its zero-force equation) plus the measured tendon tensions through the tendon Jacobian,
``y = effort - ten_J^T T`` (a tension pulls its tendon shorter). The model side starts with
MuJoCo's inverse dynamics of the given model at the conditioned ``q, qd, qdd``
(:data:`cablelab.model.KNOWN_OUTPUT`); effects add their columns (:mod:`.effects`). When the
bag carries the measured tendons' lengths (``cable_tensions`` position), one length channel per
tendon follows the joint channels (:mod:`.tendon`).
"""
from __future__ import annotations

import numpy as np

from ...conditioning import Conditioning, condition_motion
from ...errors import CablelabError
from ...dataset import Dataset
from ...model import KNOWN_OUTPUT
from ...plant_interface import DatasetOptions
from ...timebase import interp_columns
from .description import section_of
from .inverse import body_columns, inverse_record, point_mass_columns
from .mjcf import HINGE, dof_joints, names
from .topics import JOINT_STATE, topic


def dataset_from_arrays(t, q, effort, description, options: DatasetOptions | None = None, *, qd=None,
                        tension=None, lengths=None, driven=None, source: str = "data") -> Dataset:
    """Dataset from raw arrays in the model's dof order.

    Args:
        t: (N,) s; q: (N, nv) joint positions; effort: (N, nv) measured generalised forces
            (0 for a joint without actuator); qd: optional measured velocities (N, nv).
        tension: (N, n_tendons) measured tensions of the section's ``tendons`` (N), or None.
        lengths: ``{tendon: (N,) m}`` the lengths the winch encoders read of some of those
            tendons, or None: a length channel each (:func:`.tendon.with_length_channels`).
        driven: (nv,) bool, the joints whose effort is measured (default: every joint).
        description: a :class:`~cablelab.description.Description` with an ``mjcf`` section.
    """
    sec = section_of(description)
    model = sec.compiled(description.gravity)
    joints = dof_joints(model)
    opts = options.conditioning if options is not None else Conditioning()
    jtype = [model.jnt_type[names(model, "joint").index(j)] for j in joints]
    revolute = np.array([jt == HINGE for jt in jtype])
    with_tendons = bool(sec.tendons)
    lengths = dict(lengths or {}) if with_tendons else {}
    measured = np.asarray(effort, float).reshape(len(t), -1)
    if lengths:  # a length reading is a measured output too: conditioned like the efforts
        measured = np.column_stack([measured] + [np.asarray(v, float) for v in lengths.values()])
    c = condition_motion(np.asarray(t, float), np.asarray(q, float).reshape(len(t), -1),
                         measured, opts, revolute=revolute,
                         qd=None if qd is None else np.asarray(qd, float), source=source)
    q_c, qd_c, qdd_c = c["q"], c["qd"], c["qdd"]
    y = c["effort"][:, :len(joints)].copy()
    rec = inverse_record(model, q_c, qd_c, qdd_c, tendons=with_tendons,
                         kinematics=bool(sec.payload_body))
    tau, ten_j = rec.tau, rec.ten_j
    driven = np.ones(len(joints), bool) if driven is None else np.asarray(driven, bool)
    signals = {"q": q_c, "qd": qd_c, "qdd": qdd_c, KNOWN_OUTPUT: tau, "cutoff_hz": c["cutoff_hz"],
               "driven": driven,
               "rest_velocity": c["qd_smooth"], "load_warnings": list(c["warnings"]) + list(sec.warnings)}
    if with_tendons:
        tn = names(model, "tendon")
        idx = [tn.index(x) for x in sec.tendons]
        tens = interp_columns(c["t"], t, np.asarray(tension, float)[:, : len(idx)])
        jt = ten_j[:, idx, :]                                   # (N, n_meas, nv)
        y = y - np.einsum("nkv,nk->nv", jt, tens)
        signals.update({"ten_J": jt, "tension": tens})
    if sec.payload_body:
        body = names(model, "body").index(sec.payload_body)
        cols = body_columns(model, rec, body)
        signals["payload_columns"] = point_mass_columns(cols, model.body_ipos[body])
        signals["payload_com0"] = np.array(model.body_ipos[body], float)
    units = tuple("N m" if r else "N" for r in revolute)
    act_units = tuple(("N m", "rad") if r else ("N", "m") for r in revolute)
    ds = Dataset(
        plant="mjcf", t=c["t"], y=y, channels=tuple(joints), units=units, signals=signals,
        actuators=tuple(joints), act_vel=qd_c, act_units=act_units,
        inputs={f"{j} velocity": c["qd_smooth"][:, k] for k, j in enumerate(joints)},
        description=description, source=source)
    if lengths:
        from .tendon import with_length_channels

        rigid = rec.ten_length[:, [names(model, "tendon").index(x) for x in lengths]]
        ds = with_length_channels(ds, tuple(lengths), c["effort"][:, len(joints):], rigid)
    if c["parallel_hz"]:
        from ...parallel_filter import edge_mask

        ds = ds.replace(parallel_hz=c["parallel_hz"], valid=ds.valid & edge_mask(ds.t, c["parallel_hz"]))
    from ...velocity import exclude_zero_speed, position_quantum, speed_resolution

    q_raw = np.asarray(q, float).reshape(len(t), -1)
    floor = np.array([0.0 if qd is not None else speed_resolution(position_quantum(q_raw[:, k]), c["cutoff_hz"])
                      for k in range(q_raw.shape[1])])
    if not driven.any():   # no drive, no drive friction to leave its zero-speed zone out for (the
        # platform joints of a cable robot, moved by its measured tensions, rest one at a time)
        return ds.replace(signals={**ds.signals, "zero_speed_zone": np.zeros(0), "rest_share": 0.0})
    return exclude_zero_speed(ds, floor=floor)


def dataset(bag, description, options: DatasetOptions | None = None) -> Dataset:
    """Dataset of a bag: ``joint_states`` (remappable) onto the model's joints, tensions of the
    section's ``tendons`` from ``cable_tensions``."""
    sec = section_of(description)
    model = sec.compiled()
    joints = dof_joints(model)
    js_topic = topic(sec, "joint_states")
    bag.require(js_topic, JOINT_STATE)
    js = bag.joint_state(js_topic)
    missing = [j for j in joints if j not in js.names]
    if missing:
        raise CablelabError(f"{bag.path}: {js_topic} has no joint {missing[0]!r} of the model "
                            f"(model joints: {', '.join(joints)}; bag joints: {', '.join(js.names) or 'none'})")
    extra = [j for j in js.names if j not in joints]
    if extra:
        raise CablelabError(f"{bag.path}: {js_topic} joint {extra[0]!r} is not in the model "
                            f"(model joints: {', '.join(joints)})")
    idx = [js.names.index(j) for j in joints]
    q = js.position[:, idx]
    eff = js.effort[:, idx] if js.effort.size else np.full(q.shape, np.nan)
    measured = set(sec.joints) if sec.joints is not None else None
    from .mjcf import actuated_joints

    driven = set(actuated_joints(model)) if measured is None else measured
    has_effort = np.ones(len(joints), bool)
    for k, j in enumerate(joints):
        if not np.isfinite(q[:, k]).any():
            raise CablelabError(f"{bag.path}: {js_topic} has no position values for joint {j!r}")
        finite = np.isfinite(eff[:, k])
        # an undriven joint's effort is empty or 0 (CONTRACT): no sensor there
        if not finite.any() or (j not in driven and not eff[finite, k].any()):
            if j in driven:
                raise CablelabError(f"{bag.path}: {js_topic} has no effort values for the driven "
                                    f"joint {j!r}")
            eff[:, k] = 0.0                  # no actuator: its zero-force equation
            has_effort[k] = False
    qd = js.velocity[:, idx] if js.velocity.size else None
    distrusted = options.derived_velocity.get(js_topic, ()) if options is not None else ()
    if qd is not None and (not np.isfinite(qd).all() or any(j in distrusted for j in joints)):
        qd = None
    tension = None
    if sec.tendons:
        ct = topic(sec, "cable_tensions")
        bag.require(ct, JOINT_STATE)
        ts = bag.joint_state(ct)
        absent = [x for x in sec.tendons if x not in ts.names]
        if absent:
            raise CablelabError(f"{bag.path}: {ct} has no tendon {absent[0]!r} (bag names: "
                                f"{', '.join(ts.names) or 'none'})")
        tension = interp_columns(js.t, ts.t, ts.effort[:, [ts.names.index(x) for x in sec.tendons]])
        lengths = {x: _on_grid(js.t, ts.t, ts.position[:, ts.names.index(x)])
                   for x in sec.tendons if np.isfinite(ts.position[:, ts.names.index(x)]).any()}
    return dataset_from_arrays(js.t, q, eff, description, options, qd=qd, tension=tension,
                               lengths=lengths if sec.tendons else None, driven=has_effort,
                               source=str(bag.path))


def _on_grid(t, t_src, x):
    """``x`` sampled at ``t_src`` interpolated at ``t`` over its finite samples."""
    ok = np.isfinite(x)
    return np.interp(t, t_src[ok], x[ok])
