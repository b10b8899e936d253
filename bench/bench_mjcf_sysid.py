"""The mjcf plant's linear fit side by side with mujoco.sysid on the same bag and parameters.

A bag of the example arm (``plants/mjcf/examples/arm3.xml``) is recorded from a separate forward
simulation of the model edited to hold joint viscous friction, armature and a payload on the tool
(``plants/mjcf/sim.py``: PD tracking, 18-bit encoders, effort noise), close to continuous time as
a real machine moves: MuJoCo's RK4 at a tenth of the model's 2 ms step with the drive's torque
updated every physics step, one sample per 2 ms (recorded with the one-step explicit Euler
instead, the discrete damping acts half a step late and the continuous-time fit below reads
every armature low by damping x dt/2). The same parameters are then fitted twice from that bag:

- cablelab: ``cablelab identify --plant mjcf --effects payload_mass,joint_viscous_friction,
  joint_armature`` (the workbench: bag -> dataset with MuJoCo's inverse dynamics and the effects'
  columns -> one linear least-squares solve), standard errors -> 95 % intervals (x 1.96);
- mujoco.sysid: Gauss-Newton over finite-difference RK4 rollouts of short windows of the record
  (``plants/mjcf/rollout_fit.py``: efforts low-passed and averaged over each step as controls),
  its own 95 % intervals (which assume a white residual) and cluster-robust (sandwich) ones with
  each window a cluster: the measured efforts' noise drives each rollout, so its position error
  drifts within a window; the comparisons use the window-clustered ones.

Both wall times run from the bag on disk to the parameters with intervals. Per parameter: the
intervals overlap (``|a - b| <= ci_a + ci_b``), each interval contains the other's value, and
the two values are within their combined interval ``sqrt(ci_a^2 + ci_b^2)``, and the truth
is inside each.

    nice -n 10 ./run python bench/bench_mjcf_sysid.py [--seconds 12] [--window 0.25]
"""
from __future__ import annotations

import argparse
import math
import tempfile
import time
from pathlib import Path

#: the hidden truth: viscous friction N m s/rad, armature kg m^2, payload kg at m (tool frame)
DAMPING = {"base_yaw": 0.8, "shoulder": 1.5, "elbow": 0.6}
ARMATURE = {"base_yaw": 0.05, "shoulder": 0.08, "elbow": 0.03}
PAYLOAD = ("tool", 1.5, (0.04, 0.0, 0.0))
EFFECTS = ("payload_mass", "joint_viscous_friction", "joint_armature")
#: physics steps (RK4) per published sample: the record close to continuous time
SUBSTEPS = 10


def truth() -> dict:
    out = {f"Fv[{j}]": v for j, v in DAMPING.items()}
    out.update({f"armature[{j}]": v for j, v in ARMATURE.items()})
    out.update({"m": PAYLOAD[1], "com_x": PAYLOAD[2][0], "com_y": PAYLOAD[2][1], "com_z": PAYLOAD[2][2]})
    return out


def make_bag(path, seconds: float, seed: int = 3, damping=DAMPING, armature=ARMATURE,
             payload=PAYLOAD) -> str:
    from cablelab.plants.mjcf.examples import ARM3, text
    from cablelab.plants.mjcf.sim import Hidden, write_bag

    return write_bag(path, text(ARM3), Hidden(payload=payload, damping=damping, armature=armature),
                     duration=seconds, seed=seed, payload_body="tool", substeps=SUBSTEPS)


def cablelab_fit(bag, effects=EFFECTS) -> tuple[dict, dict, float]:
    """values, 95 % half-widths, seconds: the identify verb's machinery from the bag."""
    from cablelab import workbench

    t0 = time.perf_counter()
    plant, desc, ds = workbench.load(bag)
    rep = workbench.identify_report(ds, workbench.build_model(plant, desc, list(effects)), folds=0)
    seconds = time.perf_counter() - t0
    return ({k: v["value"] for k, v in rep.params.items()},
            {k: 1.96 * v["stderr"] for k, v in rep.params.items()}, seconds)


def rollout_fit(bag, window: float, effects=EFFECTS):
    """mujoco.sysid from the same bag (reading it included in the time)."""
    from cablelab.bags import open_bag
    from cablelab.plants.mjcf.rollout_fit import sysid_fit

    t0 = time.perf_counter()
    b = open_bag(bag)
    desc = b.description
    js = b.joint_state("/mjcf/joint_states")
    fit = sysid_fit(desc.mjcf.model, js.t, js.position, js.effort, list(js.names),
                    payload_body=desc.mjcf.payload_body, window=window,
                    effects=tuple(e for e in ("joint_viscous_friction", "joint_armature",
                                              "payload_mass") if e in effects))
    return fit, time.perf_counter() - t0


def inside(value: float, centre: float, ci: float) -> bool:
    return abs(value - centre) <= ci


def comparison(cv: dict, cc: dict, sv: dict, sc: dict, truth: dict) -> list[dict]:
    """Per parameter: both fits, and whether their 95 % intervals overlap, each holds the
    other's value, and each holds the truth."""
    return [{"name": k, "truth": v, "a": cv[k], "ca": cc[k], "b": sv[k], "cb": sc[k],
             "overlap": abs(cv[k] - sv[k]) <= cc[k] + sc[k],
             "combined": abs(cv[k] - sv[k]) <= (cc[k]**2 + sc[k]**2) ** 0.5,
             "a_holds_b": inside(sv[k], cv[k], cc[k]), "b_holds_a": inside(cv[k], sv[k], sc[k]),
             "a_truth": inside(v, cv[k], cc[k]), "b_truth": inside(v, sv[k], sc[k])}
            for k, v in truth.items()]


def yn(b: bool) -> str:
    return "yes" if b else "no"


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--seconds", type=float, default=12.0, help="record length, s")
    ap.add_argument("--window", type=float, default=0.25, help="sysid rollout window, s")
    a = ap.parse_args()
    with tempfile.TemporaryDirectory() as tmp:
        bag = make_bag(Path(tmp) / "arm3", a.seconds)
        cv, cc, ct = cablelab_fit(bag)
        fit, st = rollout_fit(bag, a.window)
    rows = comparison(cv, cc, fit.values, fit.ci95_windows, truth())
    print(f"arm3, {a.seconds:g} s at 500 Hz (RK4, {SUBSTEPS} physics steps per sample); sysid: "
          f"{fit.windows} windows of {a.window:g} s, {fit.evaluations} residual calls (each a "
          "batch of rollouts)\n")
    print("| parameter | truth | cablelab (95 %) | mujoco.sysid (95 %, windows; own) | intervals overlap "
          "| cablelab's holds sysid's value | sysid's holds cablelab's value | truth inside: cablelab / sysid |")
    print("| --- | --- | --- | --- | --- | --- | --- | --- |")
    for r in rows:
        print(f"| {r['name']} | {r['truth']:.4g} | {r['a']:.5g} +- {r['ca']:.2g} | {r['b']:.5g} +- "
              f"{r['cb']:.2g}; {fit.ci95[r['name']]:.2g} | {yn(r['overlap'])} | {yn(r['a_holds_b'])} | "
              f"{yn(r['b_holds_a'])} | {yn(r['a_truth'])} / {yn(r['b_truth'])} |")
    n = len(rows)
    print(f"\nintervals overlap: {sum(r['overlap'] for r in rows)}/{n}; the two values within "
          f"their combined interval sqrt(ci_a^2 + ci_b^2): {sum(r['combined'] for r in rows)}/{n} "
          f"(largest: {max(rows, key=lambda r: abs(r['a'] - r['b']) / math.hypot(r['ca'], r['cb']))['name']}, "
          f"{max(abs(r['a'] - r['b']) / math.hypot(r['ca'], r['cb']) for r in rows):.2f} of it); "
          f"cablelab's interval holds "
          f"sysid's value: {sum(r['a_holds_b'] for r in rows)}/{n}; sysid's holds cablelab's: "
          f"{sum(r['b_holds_a'] for r in rows)}/{n}; truth inside cablelab's / sysid's: "
          f"{sum(r['a_truth'] for r in rows)}/{n} / {sum(r['b_truth'] for r in rows)}/{n}")
    print("\n| fit | wall time, s |\n| --- | --- |")
    print(f"| cablelab identify (bag -> dataset -> one linear LS) | {ct:.2f} |")
    print(f"| mujoco.sysid (bag -> windows -> Gauss-Newton over rollouts) | {st:.2f} |")
    print(f"| speed ratio sysid / cablelab | {st / ct:.0f}x |")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
