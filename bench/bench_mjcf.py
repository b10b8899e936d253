"""Speed of the mjcf plant on a long record: a 7-joint serial arm, 60 s at 1 kHz (60 000 samples).
Prints one table: building the dataset (conditioning, MuJoCo's inverse dynamics, the payload
columns), every candidate's regressor block, the link-inertia columns of all seven links, and a
full ``diagnose`` over every candidate.

    nice -n 10 ./run python bench/bench_mjcf.py [--seconds 60] [--rate 1000]
"""
from __future__ import annotations

import argparse
import time

import numpy as np


def arm7_xml() -> str:
    """A 7-joint arm (alternating yaw / pitch axes), motors of gear 1, a tool body."""
    axes = ["0 0 1", "0 1 0"] * 4
    body, close = "", ""
    for i in range(7):
        body += (f'<body name="link{i + 1}" pos="0 0 {0.1 if i == 0 else 0.25}">'
                 f'<joint name="j{i + 1}" axis="{axes[i]}"/>'
                 f'<inertial pos="0 0 0.12" mass="{3.0 - 0.3 * i}" diaginertia="0.03 0.03 0.005"/>')
        close += "</body>"
    tool = '<body name="tool" pos="0 0 0.25"><inertial pos="0 0 0.05" mass="0.5" diaginertia="1e-3 1e-3 1e-3"/></body>'
    motors = "".join(f'<motor joint="j{i + 1}" gear="1"/>' for i in range(7))
    return (f'<mujoco model="arm7"><compiler angle="radian"/><option timestep="0.001"/>'
            f"<worldbody>{body}{tool}{close}</worldbody><actuator>{motors}</actuator></mujoco>")


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--seconds", type=float, default=60.0)
    ap.add_argument("--rate", type=float, default=1000.0)
    a = ap.parse_args()
    from cablelab.description import load_description
    from cablelab.diagnose import rank_candidates
    from cablelab.effects import get_effect
    from cablelab.model import Model
    from cablelab.plants.mjcf.dataset import dataset_from_arrays
    from cablelab.plants.mjcf.effects import _link_columns
    from cablelab.plants.mjcf.inverse import inverse_dynamics
    from cablelab.plants.mjcf.plant import PLANT
    from cablelab.plants.mjcf.sim import description_yaml, excitation

    xml = arm7_xml()
    desc = load_description(description_yaml(xml, payload_body="tool"))
    model = desc.mjcf.compiled(desc.gravity)
    t, q, qd, qdd = excitation(a.seconds, 1.0 / a.rate, model.nv, seed=1)
    effort = inverse_dynamics(model, q, qd, qdd) + np.random.default_rng(2).normal(0, 0.02, q.shape)
    rows = []
    t0 = time.perf_counter()
    ds = dataset_from_arrays(t, q, effort, desc)
    rows.append(("dataset (conditioning, mj_inverse, payload columns)", time.perf_counter() - t0))
    cands = PLANT.candidates(desc)
    t0 = time.perf_counter()
    for c in cands:
        get_effect(c, "mjcf").block(ds)
    rows.append((f"regressor blocks of the {len(cands)} candidates", time.perf_counter() - t0))
    t0 = time.perf_counter()
    _link_columns(ds.replace(signals=dict(ds.signals)))     # diagnose sees the dataset as built
    rows.append(("link_inertia columns (7 links + tool, 10 each)", time.perf_counter() - t0))
    t0 = time.perf_counter()
    d = rank_candidates(Model("mjcf", ()), ds, cands)
    rows.append((f"diagnose over the {len(cands)} candidates", time.perf_counter() - t0))
    print(f"mjcf plant, 7-joint arm, {ds.n} samples ({a.seconds:g} s at {a.rate:g} Hz); "
          f"top: {d.ranking[0].effect}")
    print(f"| {'step':<55} | {'s':>7} |")
    print(f"| {'-' * 55} | {'-' * 7} |")
    for name, s in rows:
        print(f"| {name:<55} | {s:7.2f} |")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
