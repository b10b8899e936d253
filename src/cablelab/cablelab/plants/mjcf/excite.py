"""Experiment design for the ``mjcf`` plant (``cablelab excite``): every measured joint follows
the designed Fourier series inside the limits the MuJoCo model gives, and the dataset the mjcf
effects see for such a motion.

Limits: a joint's ``range`` where the model limits it (else :data:`FREE_RANGE` around its
``qpos0``), speeds and accelerations :data:`SPEED` / :data:`ACCEL` (MJCF has none); efforts from
the actuators' ``ctrlrange`` (times the gear) or ``forcerange`` and the joint's
``actuatorfrcrange``: the designed motion's inverse dynamics must stay inside them (the
:class:`~cablelab.excite.Limits` constraint; a design that breaks one is refused).

The design grid has 5 samples per period of the highest harmonic (the crane's and the CDPR's 10):
each sample costs a MuJoCo inverse-dynamics pass with the body kinematics the payload's columns
are built from. The dataset is the one :func:`.dataset.dataset_from_arrays` builds, for a
motion that follows the reference exactly (no conditioning: q, qd, qdd are the designed ones):
MuJoCo's inverse dynamics as the known output, the payload body's columns, the tendon Jacobians.
"""
from __future__ import annotations

import numpy as np

from ...dataset import Dataset
from ...excite import Exciter, Limits
from ...model import KNOWN_OUTPUT
from .description import section_of
from .inverse import body_columns, inverse_dynamics, inverse_record, point_mass_columns
from .mjcf import HINGE, dof_joints, names
from .topics import TOPICS

#: half range around qpos0 of a joint the model leaves unlimited: rad (hinge), m (slide)
FREE_RANGE = {HINGE: 1.5, "slide": 0.3}
#: speed and acceleration limits: rad/s, rad/s^2 (hinge); m/s, m/s^2 (slide)
SPEED = {HINGE: 1.0, "slide": 0.3}
ACCEL = {HINGE: 2.0, "slide": 1.0}


def _kind(jtype) -> object:
    return HINGE if jtype == HINGE else "slide"


def effort_limits(model) -> np.ndarray:
    """(nv,) largest generalised force each dof's actuators may apply (inf: unlimited)."""
    lim = np.full(model.nv, np.inf)
    for a in range(model.nu):
        if model.actuator_trntype[a] != 0:        # joint transmission only
            continue
        dof = int(model.jnt_dofadr[model.actuator_trnid[a, 0]])
        gear = abs(float(model.actuator_gear[a, 0]))
        caps = []
        if model.actuator_ctrllimited[a]:
            caps.append(gear * np.abs(model.actuator_ctrlrange[a]).max())
        if model.actuator_forcelimited[a]:
            caps.append(np.abs(model.actuator_forcerange[a]).max())
        if caps:
            lim[dof] = min(lim[dof], min(caps)) if np.isfinite(lim[dof]) else min(caps)
    for j in range(model.njnt):
        if getattr(model, "jnt_actfrclimited", np.zeros(model.njnt))[j]:
            dof = int(model.jnt_dofadr[j])
            lim[dof] = min(lim[dof], float(np.abs(model.jnt_actfrcrange[j]).max()))
    return lim


def excite_limits(description) -> Limits:
    """Joint ranges, speeds, accelerations and the effort constraint of the model (module doc)."""
    sec = section_of(description)
    model = sec.compiled(description.gravity)
    joints = dof_joints(model)
    jn = names(model, "joint")
    lo, hi, sp, ac = [], [], [], []
    for name in joints:
        j = jn.index(name)
        kind = _kind(model.jnt_type[j])
        q0 = float(model.qpos0[model.jnt_qposadr[j]])
        if model.jnt_limited[j]:
            lo.append(float(model.jnt_range[j, 0]))
            hi.append(float(model.jnt_range[j, 1]))
        else:
            lo.append(q0 - FREE_RANGE[kind])
            hi.append(q0 + FREE_RANGE[kind])
        sp.append(SPEED[kind])
        ac.append(ACCEL[kind])
    cap = effort_limits(model)

    def constraint(q, qd, qdd):
        if not np.isfinite(cap).any():
            return []
        tau = inverse_dynamics(model, q, qd, qdd)
        over = np.abs(tau).max(axis=0) > cap
        return [f"{joints[k]}: effort {np.abs(tau[:, k]).max():.4g} above {cap[k]:.4g} (actuator limit)"
                for k in np.flatnonzero(over)]

    return Limits(tuple(joints), np.array(lo), np.array(hi), np.array(sp), np.array(ac), constraint)


def motion_dataset(t, q, qd, qdd, description) -> Dataset:
    """The mjcf dataset of a motion that follows the reference exactly (outputs zero)."""
    sec = section_of(description)
    model = sec.compiled(description.gravity)
    joints = dof_joints(model)
    jn = names(model, "joint")
    revolute = np.array([model.jnt_type[jn.index(j)] == HINGE for j in joints])
    q, qd, qdd = (np.asarray(a, float) for a in (q, qd, qdd))
    with_tendons = bool(sec.tendons)
    rec = inverse_record(model, q, qd, qdd, tendons=with_tendons, kinematics=bool(sec.payload_body))
    tau, ten_j = rec.tau, rec.ten_j
    from .mjcf import actuated_joints

    measured = set(sec.joints) if sec.joints is not None else set(actuated_joints(model))
    driven = np.array([j in measured for j in joints])
    n = len(t)
    signals = {"q": q, "qd": qd, "qdd": qdd, KNOWN_OUTPUT: tau, "driven": driven,
               "rest_velocity": qd, "load_warnings": []}
    if with_tendons:
        tn = names(model, "tendon")
        jt = ten_j[:, [tn.index(x) for x in sec.tendons], :]
        signals.update({"ten_J": jt, "tension": np.zeros((n, jt.shape[1]))})
    if sec.payload_body:
        body = names(model, "body").index(sec.payload_body)
        cols = body_columns(model, rec, body)
        signals["payload_columns"] = point_mass_columns(cols, model.body_ipos[body])
        signals["payload_com0"] = np.array(model.body_ipos[body], float)
    return Dataset(
        plant="mjcf", t=np.asarray(t, float), y=np.zeros((n, len(joints))), channels=tuple(joints),
        units=tuple("N m" if r else "N" for r in revolute), signals=signals,
        actuators=tuple(joints), act_vel=qd,
        act_units=tuple(("N m", "rad") if r else ("N", "m") for r in revolute),
        description=description, source="designed motion")


#: the mjcf plant's experiment design (``cablelab excite``), registered by the package
EXCITER = Exciter(limits=excite_limits, motion_dataset=motion_dataset,
                  reference_topic=TOPICS["reference"][0], base_hz=0.1, harmonics=5, grid=5.0)
