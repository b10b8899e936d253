"""Randomized hopping-leg diagnosis cases (bench_diagnosis.py), generated WITHOUT the fitting code.

* truth: the leg's independent reference, :func:`cablelab.plants.leg.reference.sampled_trajectory`
  (scipy ``solve_ivp`` per phase with terminal events, rtol 1e-10; it shares nothing with the
  MuJoCo plant or the workbench's linear inverse model but the physical laws of 003 eq. 1, 23,
  24, 26), under the open-loop stance torque ``T sin(2 pi (t - t_d) / P)`` of eq. 26 with random
  T and P, started from a drop.
* sensors (003 sec. 3.1, the reference's measurement model): 0.09 mm encoder with a random zero,
  backward-difference velocity, contact switch; plus AR(1) noise with outliers on the recorded
  motor torque (1-3 % of its RMS); 1 kHz.

Every run has the impacts of eq. 24 (beta_td 0.5-0.85, beta_lo 1.02-1.15, as 003 Table 2).
Hidden effects, one per case, from the leg's candidates (``cablelab.plants.leg``):
``impact_restitution`` (not in the nominal model), ``spring_preload`` (F_0),
``guide_coulomb_friction`` (F_c), ``phase_effective_mass`` (m_f != m), plus control cases
(nothing hidden). The nominal model is the plant's (``leg_inertia``, ``stance_damping``,
``flight_damping``) + ``impact_restitution`` (``--effects``) except when that is the hidden one.

Designed preload/mass cases (``draw_designed_case``, ``run_designed_case``; run by
``bench_diagnosis.py --designed leg=N``): low hops that confound the preload with the mass, the
apex-height schedule ``cablelab excite`` designs on them, the weighed mass (see the section below).
"""
from __future__ import annotations

import numpy as np

from cases_common import PlantCase, coloured_noise

ONE = [("impact_restitution",), ("spring_preload",), ("guide_coulomb_friction",), ("phase_effective_mass",)]

DESCRIPTION = """plant: leg
gravity: 9.81
leg:
  mass: {mass:.3f}
  spring_stiffness: 605.0
  link_length: 0.15
  free_angle: 0.349066
  spring_preload: 0.0
  encoder_resolution: 9.0e-5
"""


def draw_case(seed: int, kind: str | None = None) -> PlantCase:
    """A random leg case. ``kind``: "control" or "one" (default drawn 25/75 %)."""
    rng = np.random.default_rng(seed)
    if kind is None:
        kind = str(rng.choice(["control", "one"], p=[0.25, 0.75]))
    hidden = () if kind == "control" else ONE[rng.integers(len(ONE))]
    m = rng.uniform(1.45, 1.7)
    truth = {"m": m, "d_s": rng.uniform(4.0, 8.0), "d_f": rng.uniform(0.8, 1.5),
             "beta_td": rng.uniform(0.5, 0.85), "beta_lo": rng.uniform(1.02, 1.15),
             "F0": 0.0, "Fc": 0.0, "m_f": m, "T": rng.uniform(1.5, 3.0), "P": rng.uniform(0.26, 0.38),
             "duration": rng.uniform(12.0, 20.0), "z_drop": rng.uniform(0.02, 0.05),
             "noise_rel": 10 ** rng.uniform(-2, np.log10(0.03)), "ar": rng.uniform(0, 0.8),
             "outlier_rate": float(rng.choice([0.0, 0.002]))}
    if "spring_preload" in hidden:
        truth["F0"] = rng.uniform(1.5, 4.0)
    if "guide_coulomb_friction" in hidden:
        truth["Fc"] = rng.uniform(0.4, 1.2)
    if "phase_effective_mass" in hidden:
        truth["m_f"] = m + rng.choice([-1, 1]) * rng.uniform(0.12, 0.3)
    effects = () if "impact_restitution" in hidden else ("impact_restitution",)
    # the leg is weighed (003 sec. 3.3: 1.62 kg on a scale, 1 g resolution): its mass m_f is known
    # (``--fix m``). Without it the stance weight m_f g and a spring preload F_0 are one constant
    # stance force, and phase_effective_mass is spring_preload (module docstring)
    weighed = round(truth["m_f"], 3)
    case = PlantCase(plant="leg", seed=seed, family="", fs=1000.0, hidden=tuple(hidden), effects=effects,
                     description=DESCRIPTION.format(mass=weighed), truth=truth, velocity_recorded=True,
                     fixed={"m": weighed})
    tp = {"impact_restitution": {"c_td": m * (1 - truth["beta_td"]), "c_lo": m * (1 - truth["beta_lo"])},
          "spring_preload": {"F0": truth["F0"]}, "guide_coulomb_friction": {"Fc": truth["Fc"]},
          "phase_effective_mass": {"dm_f": truth["m_f"] - m}}
    case.true_params = {h: tp[h] for h in hidden}
    return case


#: shortest flight a 1 kHz contact switch records as an open switch (a few samples), s
MIN_FLIGHT_S = 0.005


def shortest_flight(events) -> float:
    """Shortest lift-off-to-touch-down time among the truth events (inf without a flight), s."""
    gaps = [b.t - a.t for a, b in zip(events[:-1], events[1:]) if a.kind == "liftoff" and b.kind == "touchdown"]
    return min(gaps, default=np.inf)


def simulate(case: PlantCase):
    """The reference run, measured (:class:`cablelab.plants.leg.sim.Trajectory`), with noise on
    the recorded torque."""
    from cablelab.plants.leg.hybrid import LegParams
    from cablelab.plants.leg.reference import sampled_trajectory

    tr = case.truth
    p = LegParams(m=tr["m"], d_s=tr["d_s"], d_f=tr["d_f"], beta_td=tr["beta_td"], beta_lo=tr["beta_lo"],
                  F0=tr["F0"], Fc=tr["Fc"], m_f=tr["m_f"])
    redraw = np.random.default_rng(case.seed + 104729)
    for _ in range(20):
        # some (T, P) settle into a bounce without flight, others into stances longer than P / 2
        # whose negative eq. 26 torque drives F_GRF to 0 while the body still moves down: the
        # hybrid model then lifts off and touches down again within a fraction of a sample (both
        # impact maps, torque restarted) and the sampled contact switch never opens. A recording
        # whose switch misses transitions is not a valid leg experiment: draw another excitation
        traj = sampled_trajectory(p, p.z_td + tr["z_drop"], 0.0, tr["duration"], T=tr["T"], P=tr["P"],
                                  seed=case.seed)
        if np.mean(traj.phase == 0) >= 0.05 and shortest_flight(traj.events) >= MIN_FLIGHT_S:
            break
        tr["T"], tr["P"] = redraw.uniform(1.5, 3.0), redraw.uniform(0.26, 0.38)
    else:
        raise RuntimeError(f"case {case.seed}: no excitation with clean hops (T {tr['T']:.2f} N m, "
                           f"P {tr['P']:.3f} s)")
    rng = np.random.default_rng(case.seed + 7919)
    sigma = tr["noise_rel"] * float(np.sqrt(np.mean(traj.tau ** 2)))
    traj.tau = traj.tau + coloured_noise(rng, traj.tau.size, sigma, tr["ar"], tr["outlier_rate"])
    return traj


def write_bag(case: PlantCase, path, rec=None):
    """Simulate (unless ``rec`` is given) and write the leg bag (``/leg/joint_states`` body height
    and motor torque, ``/leg/contact``, ``/plant_description``; the bag layout of the leg's own
    writer, :func:`cablelab.plants.leg.sim.write_bag`)."""
    from cablelab.plants.leg.sim import write_bag as leg_write_bag

    rec = rec if rec is not None else simulate(case)
    leg_write_bag(path, rec, case.description, overwrite=True)
    return rec


# ----------------------------------------------------------------------------- designed experiments
#
# Preload against mass. With the leg's mass free, low hops of one height see the stance force
# m (zdd + g) - F_0 nearly as one column (F_0 and m confounded; a stance inertia m_s and a weight
# m_f g differ from it only by the same constant). The designed cases: a first recording of low
# hops under the apex-height controller, ``cablelab excite`` for (F_0, m) on it, the designed
# apex-height schedule played by the same controller, and ``diagnose --greedy`` on that run with
# the mass weighed (fixed at the scale's value, up to WEIGHING_ERROR off). Truth: the hybrid MuJoCo
# leg (plants/leg/sim.py, events located inside the step) under the live estimator and the apex
# controller (plants/leg/excite.py ``closed_loop``), sharing nothing with the linear inverse model
# the diagnosis fits but 003's laws; the controller knows only the description (nominal damping
# and impact ratios, the weighed mass).

#: the pair the design separates (mass free)
PAIR = ("F0", "m")
#: relative error of the scale the leg is weighed on (uniform within +-)
WEIGHING_ERROR = 0.005
#: apex height of the first recording's low hops above z_td, m
LOW_HOPS = 0.004


def draw_designed_case(seed: int, kind: str | None = None) -> PlantCase:
    """A designed preload/mass case. ``kind``: "preload" (a spring preload F_0 of 1.5-4 N hidden),
    "mass" (a stance inertia m_s 0.12-0.3 kg away from the weighed mass m_f hidden:
    ``phase_effective_mass``) or "control" (nothing hidden); default drawn 40/40/20 %."""
    rng = np.random.default_rng(seed)
    if kind is None:
        kind = str(rng.choice(["preload", "mass", "control"], p=[0.4, 0.4, 0.2]))
    m_f = rng.uniform(1.45, 1.7)
    truth = {"m": m_f, "m_f": m_f, "d_s": rng.uniform(5.0, 7.5), "d_f": rng.uniform(0.8, 1.5),
             "beta_td": rng.uniform(0.5, 0.7), "beta_lo": rng.uniform(1.05, 1.15), "F0": 0.0,
             "noise_rel": 10 ** rng.uniform(-2, np.log10(0.03)), "ar": rng.uniform(0, 0.8),
             "outlier_rate": float(rng.choice([0.0, 0.002])), "first_s": 20.0, "designed_s": 30.0}
    hidden = {"preload": ("spring_preload",), "mass": ("phase_effective_mass",), "control": ()}[kind]
    if kind == "preload":
        truth["F0"] = rng.uniform(1.5, 4.0)
    if kind == "mass":
        truth["m"] = m_f - rng.choice([-1, 1]) * rng.uniform(0.12, 0.3)      # the stance inertia m_s
    weighed = round(m_f * (1 + rng.uniform(-WEIGHING_ERROR, WEIGHING_ERROR)), 4)
    truth["weighed"] = weighed
    case = PlantCase(plant="leg", seed=seed, family=f"designed {kind}", fs=1000.0, hidden=hidden,
                     effects=("impact_restitution",), description=DESCRIPTION.format(mass=weighed),
                     truth=truth, velocity_recorded=True, fixed={"m": weighed})
    tp = {"spring_preload": {"F0": truth["F0"]}, "phase_effective_mass": {"dm_f": m_f - truth["m"]}}
    case.true_params = {h: tp[h] for h in hidden}
    return case


def _params(case: PlantCase):
    from cablelab.plants.leg.hybrid import LegParams

    tr = case.truth
    return LegParams(m=tr["m"], m_f=tr["m_f"], d_s=tr["d_s"], d_f=tr["d_f"], beta_td=tr["beta_td"],
                     beta_lo=tr["beta_lo"], F0=tr["F0"])


def play(case: PlantCase, h_des, duration: float, path) -> None:
    """The leg under the apex controller (nominal = the case's description) following ``h_des``
    (absolute apex height, m, or a function of time), measured, with coloured noise and outliers
    on the recorded torque; written as a leg bag."""
    from cablelab.description import load_description
    from cablelab.plants.leg.description import leg_of
    from cablelab.plants.leg.excite import closed_loop
    from cablelab.plants.leg.sim import write_bag as leg_write_bag

    desc = load_description(case.description)
    nominal = leg_of(desc).params(desc.gravity)
    tr = case.truth
    traj = closed_loop(_params(case), h_des, duration, controller_params=nominal, seed=case.seed)
    rng = np.random.default_rng(case.seed + 7919 + int(duration))
    sigma = tr["noise_rel"] * float(np.sqrt(np.mean(traj.tau ** 2)))
    traj.tau = traj.tau + coloured_noise(rng, traj.tau.size, sigma, tr["ar"], tr["outlier_rate"])
    leg_write_bag(path, traj, case.description, overwrite=True)


def run_designed_case(case: PlantCase, workdir: str, diagnose_case) -> dict:
    """One designed case: low hops (the first recording), ``cablelab excite`` for :data:`PAIR` on
    it, the designed schedule played, ``diagnose_case`` (bench_diagnosis: ``diagnose --greedy``
    with the case's effects and the weighed mass) on that run. Adds ``cond`` (excite's condition
    number of (F_0, m), first -> designed), ``fit_cond`` (the condition number of F_0 against the
    stance mass dm_f in the fitted model with the mass weighed, first -> designed) and
    ``design_s``."""
    import os
    import time

    from cablelab import workbench
    from cablelab.excite import condition, design

    def weighed_condition(path):
        plant, desc, ds = workbench.load(path)
        model = workbench.build_model(plant, desc, ("impact_restitution", "spring_preload",
                                                    "phase_effective_mass"), fixed=case.fixed)
        return ds, desc, condition(model, ds, ("F0", "dm_f"))

    tr = case.truth
    fields = {"case": case, "plant": case.plant, "hidden": tuple(case.hidden), "label": case.label(),
              "family": (case.family, int(case.fs), "velocity"), "miss": f"seed {case.seed} leg {case.family}"}
    first = os.path.join(workdir, f"leg_{case.seed}_first")
    z_td = _params(case).z_td
    try:
        play(case, z_td + LOW_HOPS, tr["first_s"], first)
        ds0, desc, c0 = weighed_condition(first)
        t0 = time.perf_counter()
        d = design("leg", desc, PAIR, duration=tr["designed_s"], before_ds=ds0, seed=case.seed, max_iter=10)
        design_s = time.perf_counter() - t0
        path = os.path.join(workdir, f"leg_{case.seed}_designed")
        play(case, lambda t: np.interp(t, d.t, d.q[:, 0]), tr["designed_s"], path)
    except RuntimeError as exc:
        return {**fields, "error": f"generator: {exc}", "seconds": 0.0}
    r = diagnose_case(case, path, fields)
    r.update(cond=(d.condition_before, d.condition_after), fit_cond=(c0, weighed_condition(path)[2]),
             design_s=design_s)
    return r
