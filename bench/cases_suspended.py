"""Randomized suspended-platform diagnosis cases (bench_diagnosis.py), generated WITHOUT the fitting
code.

* truth: the LiCAS *truth plant* of :func:`cablelab.plants.suspended.mjcf.build_truth` - a free
  platform with its two arms hung by four length-limited spatial tendons (a quadrifilar pendulum,
  spec 000 sec. 3.3), not the virtual-joint chain whose reduction the workbench fits (000 eq. 1:
  swing equations per mode). Released from a random swing (and in the yaw cases a yaw twist);
  stepped by MuJoCo at 1 ms with the hidden cable/air forces applied to the platform each step:
  viscous ``-(f_v / L^2) v`` (always: the nominal model has it), SMOOTH Coulomb
  ``-(f_s / L) tanh(v / (L eps))`` and quadratic drag ``-c |v| v`` per horizontal axis.
* sensors: the platform pose by motion capture at 100 Hz with 0.3-1 mm noise; a pose-sensor offset
  (the measured rest position shifted by 5-15 mm) as a hidden effect.

Hidden effects, one per case, from the plant's candidates (``cablelab.plants.suspended``):
``cable_joint_coulomb_friction``, ``air_drag``, ``pose_sensor_offset``, ``virtual_yaw_stiffness``
(the yaw return of the four cables: present whenever the platform twists, so hidden exactly in
the cases that start with a yaw twist), plus control cases. Detection only: the fitted swing
parameters carry the ratio of the description's nominal modal inertia to the truth plant's, so
their values are not compared with the truth.
"""
from __future__ import annotations

import numpy as np

from cases_common import PlantCase

ONE = [("cable_joint_coulomb_friction",), ("air_drag",), ("pose_sensor_offset",), ("virtual_yaw_stiffness",)]
DESCRIPTION = "plant: suspended\nname: licas truth\nsuspended:\n  variant: licas\n"


def draw_case(seed: int, kind: str | None = None) -> PlantCase:
    """A random suspended case. ``kind``: "control" or "one" (default drawn 25/75 %), or "stops":
    Coulomb friction strong enough to stop the swing dead within the first 20 s of a 60 s
    record (``stopping_case``; not in the default draw)."""
    if kind == "stops":
        return stopping_case(seed)
    rng = np.random.default_rng(seed)
    if kind is None:
        kind = str(rng.choice(["control", "one"], p=[0.25, 0.75]))
    hidden = () if kind == "control" else ONE[rng.integers(len(ONE))]
    truth = {"swing_x": rng.choice([-1, 1]) * rng.uniform(0.12, 0.25),
             "swing_y": rng.choice([-1, 1]) * rng.uniform(0.12, 0.25),
             "yaw": rng.choice([-1, 1]) * rng.uniform(0.2, 0.4) if "virtual_yaw_stiffness" in hidden else 0.0,
             "fv": rng.uniform(0.5, 2.0), "fs": 0.0, "c": 0.0, "offset": np.zeros(3), "eps": 0.005,
             "duration": rng.uniform(12.0, 20.0), "mocap_noise": rng.uniform(3e-4, 1e-3)}
    if "cable_joint_coulomb_friction" in hidden:
        truth["fs"] = rng.uniform(0.03, 0.08)
    if "air_drag" in hidden:
        truth["c"] = rng.uniform(0.8, 2.5)
    if "pose_sensor_offset" in hidden:
        truth["offset"] = np.r_[rng.choice([-1, 1], 2) * rng.uniform(0.005, 0.015, 2), 0.0]
    return PlantCase(plant="suspended", seed=seed, family="", fs=100.0, hidden=tuple(hidden),
                     description=DESCRIPTION, truth=truth)


def stopping_case(seed: int, fs: float | None = None, duration: float = 60.0) -> PlantCase:
    """A free swing that dry friction in the suspension stops dead: f_s drawn 0.15-0.4 N m (the
    swing of 0.12-0.25 rad dies within 5-20 s), light viscous friction, ``duration`` s recorded,
    most of it at rest. ``fs=0``: the same record without friction (its control)."""
    rng = np.random.default_rng(seed)
    fs = float(rng.uniform(0.15, 0.4)) if fs is None else float(fs)
    truth = {"swing_x": rng.choice([-1, 1]) * rng.uniform(0.12, 0.25),
             "swing_y": rng.choice([-1, 1]) * rng.uniform(0.12, 0.25), "yaw": 0.0,
             "fv": rng.uniform(0.2, 0.5), "fs": fs, "c": 0.0, "offset": np.zeros(3), "eps": 0.005,
             "duration": float(duration), "mocap_noise": rng.uniform(3e-4, 1e-3)}
    hidden = ("cable_joint_coulomb_friction",) if fs > 0 else ()
    return PlantCase(plant="suspended", seed=seed, family="stops", fs=100.0, hidden=hidden,
                     description=DESCRIPTION, truth=truth)


def simulate(case: PlantCase) -> dict:
    """Free swing of the tendon truth plant with the hidden forces; returns ``t``, measured ``pos``
    (N, 3) and ``quat`` (N, 4) w, x, y, z at 100 Hz."""
    import mujoco

    from cablelab.plants.suspended.mjcf import build_truth
    from cablelab.plants.suspended.params import parameter_set
    from cablelab.plants.suspended.sim import STATE_SPEC, truth_start

    tr = case.truth
    p = parameter_set("licas")
    model = build_truth(p)
    data = mujoco.MjData(model)
    mujoco.mj_setState(model, data, truth_start(model, p, tr["swing_x"], tr["swing_y"], tr["yaw"]), STATE_SPEC)
    mujoco.mj_forward(model, data)
    bid = model.body("platform").id
    L = p.L
    dt = model.opt.timestep
    n = int(round(tr["duration"] / dt))
    every = int(round(1.0 / (case.fs * dt)))
    m = (n + every - 1) // every
    pos, quat = np.empty((m, 3)), np.empty((m, 4))
    vel = np.empty(6)
    j = 0
    for k in range(n):  # MuJoCo stepping with the hidden forces of this state (truth only)
        mujoco.mj_objectVelocity(model, data, mujoco.mjtObj.mjOBJ_BODY, bid, vel, 0)
        v = vel[3:5]                                   # horizontal platform velocity, world frame
        f = -(tr["fv"] / L**2) * v - (tr["fs"] / L) * np.tanh(v / (L * tr["eps"])) - tr["c"] * np.abs(v) * v
        data.xfrc_applied[bid, :2] = f
        if k % every == 0:
            mujoco.mj_forward(model, data)
            pos[j], quat[j] = data.sensordata[0:3], data.sensordata[3:7]
            j += 1
        mujoco.mj_step(model, data)
    rng = np.random.default_rng(case.seed + 7919)
    meas = pos + tr["offset"] + rng.normal(0, tr["mocap_noise"], pos.shape)
    return {"t": np.arange(m) / case.fs, "pos": meas, "quat": quat, "pos_true": pos}


def write_bag(case: PlantCase, path, rec: dict | None = None) -> dict:
    """Simulate (unless ``rec`` is given) and write ``/suspended/platform_pose`` +
    ``/plant_description``."""
    from cablelab.bags import BagWriter

    rec = rec if rec is not None else simulate(case)
    q = rec["quat"]
    with BagWriter(path, overwrite=True) as w:
        w.write_description(case.description)
        w.write_poses("/suspended/platform_pose", rec["t"] + 1.0, rec["pos"], q[:, [1, 2, 3, 0]])
    return rec
