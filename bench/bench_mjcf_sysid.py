"""The mjcf plant's linear fit side by side with mujoco.sysid on the same bag and parameters.

A bag of the example arm (``plants/mjcf/examples/arm3.xml``) is recorded from a separate forward
simulation of the model edited to hold joint viscous friction, armature and a payload on the tool
(``plants/mjcf/sim.py``: MuJoCo's explicit Euler, PD tracking, 18-bit encoders, effort noise).
The same parameters are then fitted twice from that bag:

- cablelab: ``cablelab identify --plant mjcf --effects payload_mass,joint_viscous_friction,
  joint_armature`` (the workbench: bag -> dataset with MuJoCo's inverse dynamics and the effects'
  columns -> one linear least-squares solve), standard errors -> 95 % intervals (x 1.96);
- mujoco.sysid: Gauss-Newton over finite-difference rollouts of short windows of the record
  (``plants/mjcf/rollout_fit.py``), its own 95 % intervals (which assume a white residual) and
  those widened for the rollout residual's lag-1 autocorrelation r1 by sqrt((1 + r1)/(1 - r1)),
  the rule cablelab applies to its own intervals.

Both wall times run from the bag on disk to the parameters with intervals. "agree" is
``|cablelab - sysid| <= sqrt(ci_cablelab^2 + ci_sysid^2)``, with sysid's own intervals ("own")
and with the widened ones ("widened").

    nice -n 10 ./run python bench/bench_mjcf_sysid.py [--seconds 12] [--window 0.5]
"""
from __future__ import annotations

import argparse
import tempfile
import time
from pathlib import Path

#: the hidden truth: viscous friction N m s/rad, armature kg m^2, payload kg at m (tool frame)
DAMPING = {"base_yaw": 0.8, "shoulder": 1.5, "elbow": 0.6}
ARMATURE = {"base_yaw": 0.05, "shoulder": 0.08, "elbow": 0.03}
PAYLOAD = ("tool", 1.5, (0.04, 0.0, 0.0))
EFFECTS = ("payload_mass", "joint_viscous_friction", "joint_armature")


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
                     duration=seconds, seed=seed, payload_body="tool")


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


def agree(a: float, ca: float, b: float, cb: float) -> bool:
    return abs(a - b) <= (ca**2 + cb**2) ** 0.5


def yn(b: bool) -> str:
    return "yes" if b else "no"


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--seconds", type=float, default=12.0, help="record length, s")
    ap.add_argument("--window", type=float, default=0.5, help="sysid rollout window, s")
    a = ap.parse_args()
    with tempfile.TemporaryDirectory() as tmp:
        bag = make_bag(Path(tmp) / "arm3", a.seconds)
        cv, cc, ct = cablelab_fit(bag)
        fit, st = rollout_fit(bag, a.window)
    rows = ["| parameter | truth | cablelab (95 %) | mujoco.sysid (95 %: own; widened) | agree: own / widened "
            "| truth inside: cablelab / sysid own / widened |", "| --- | --- | --- | --- | --- | --- |"]
    n_agree = n_own = 0
    for k, v in truth().items():
        ok_own = agree(cv[k], cc[k], fit.values[k], fit.ci95[k])
        ok = agree(cv[k], cc[k], fit.values[k], fit.ci95_inflated[k])
        n_agree += ok
        n_own += ok_own
        sv, sc, sw = fit.values[k], fit.ci95[k], fit.ci95_inflated[k]
        rows.append(f"| {k} | {v:.4g} | {cv[k]:.5g} +- {cc[k]:.2g} | {sv:.5g} +- {sc:.2g}; {sw:.2g} | "
                    f"{yn(ok_own)} / {yn(ok)} | {yn(abs(cv[k] - v) <= cc[k])} / "
                    f"{yn(abs(sv - v) <= sc)} / {yn(abs(sv - v) <= sw)} |")
    print(f"arm3, {a.seconds:g} s at 500 Hz; sysid: {fit.windows} windows of {a.window:g} s, "
          f"{fit.evaluations} residual calls (each a batch of rollouts)")
    print("\n".join(rows))
    print(f"\nagree within the intervals: {n_own}/{len(rows) - 2} with sysid's own, "
          f"{n_agree}/{len(rows) - 2} with the widened ones")
    print("\n| fit | wall time, s |\n| --- | --- |")
    print(f"| cablelab identify (bag -> dataset -> one linear LS) | {ct:.2f} |")
    print(f"| mujoco.sysid (bag -> windows -> Gauss-Newton over rollouts) | {st:.2f} |")
    print(f"| speed ratio sysid / cablelab | {st / ct:.0f}x |")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
