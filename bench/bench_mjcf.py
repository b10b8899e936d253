"""Speed of the mjcf plant on a long record: a 7-joint serial arm, 60 s at 1 kHz (60 000 samples).
Prints one table: building the dataset (conditioning, MuJoCo's inverse dynamics, the payload
columns), every candidate's regressor block, the link-inertia columns of all eight moving bodies,
a full ``diagnose`` over every candidate, and the ROS-free simulator of
``cable_sim_node --plant mjcf`` (:class:`cablelab.plants.mjcf.sim.MjcfSim`: one ``advance`` and
one ``state`` per physics step, what the node does per period at its default rate) against a bare
``mujoco.mj_step`` loop on the same model for the same simulated time, in the same run.

Each row gives wall-clock seconds and the CPU seconds of this process (``time.process_time``:
on a shared machine the wall clock also counts other people's work) and the target of the row.
The link-inertia columns are built on a copy of the dataset, so the diagnosis sees the dataset as
the ``diagnose`` verb builds it (``link_inertia`` is not one of its candidates).

    nice -n 10 ./run python bench/bench_mjcf.py [--seconds 60] [--rate 1000] [--sim-seconds 10]
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


class Clock:
    """Wall and CPU seconds of a block."""

    def __enter__(self):
        self.w0, self.c0 = time.perf_counter(), time.process_time()
        return self

    def __exit__(self, *exc):
        self.wall, self.cpu = time.perf_counter() - self.w0, time.process_time() - self.c0


def sim_vs_bare(desc, seconds: float, repeat: int = 3) -> tuple[tuple, tuple, int]:
    """The node's simulator and a bare mj_step loop, ``seconds`` of simulated time each, from the
    model's initial state with the same (zero) controls, alternated ``repeat`` times. Returns the
    best ``(wall, cpu)`` of each and the step count."""
    import mujoco

    from cablelab.plants.mjcf.sim import MjcfSim

    model = desc.mjcf.compiled(desc.gravity)
    n = int(round(seconds / model.opt.timestep))
    ctrl = np.zeros(model.nu)
    best_node, best_bare = [np.inf, np.inf], [np.inf, np.inf]
    for _ in range(repeat):
        sim = MjcfSim(desc.mjcf, desc.gravity)
        dt = sim.model.opt.timestep
        with Clock() as node:
            for _ in range(n):
                sim.advance(ctrl, dt)
                sim.state()
        data = mujoco.MjData(model)
        step = mujoco.mj_step
        with Clock() as bare:
            for _ in range(n):
                step(model, data)
        best_node = [min(best_node[0], node.wall), min(best_node[1], node.cpu)]
        best_bare = [min(best_bare[0], bare.wall), min(best_bare[1], bare.cpu)]
    return tuple(best_node), tuple(best_bare), n


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--seconds", type=float, default=60.0)
    ap.add_argument("--rate", type=float, default=1000.0)
    ap.add_argument("--sim-seconds", type=float, default=10.0, help="simulated time of the sim rows")
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
    with Clock() as c_ds:
        ds = dataset_from_arrays(t, q, effort, desc)
    cands = PLANT.candidates(desc)
    with Clock() as c_blocks:
        for c in cands:
            get_effect(c, "mjcf").block(ds)
    with Clock() as c_link:
        _link_columns(ds.replace(signals=dict(ds.signals)))
    regress = (c_ds.wall + c_blocks.wall + c_link.wall, c_ds.cpu + c_blocks.cpu + c_link.cpu)
    rows.append(("dataset (conditioning, mj_inverse, payload columns)", c_ds.wall, c_ds.cpu, ""))
    rows.append((f"regressor blocks of the {len(cands)} candidates", c_blocks.wall, c_blocks.cpu, ""))
    rows.append(("link_inertia columns (7 links + tool, 10 each)", c_link.wall, c_link.cpu, ""))
    rows.append(("inverse dynamics + every regressor (3 rows above)", *regress, "< 5 s"))
    with Clock() as c_diag:
        d = rank_candidates(Model("mjcf", ()), ds, cands)
    rows.append((f"diagnose over the {len(cands)} candidates", c_diag.wall, c_diag.cpu, "< 15 s"))
    node, bare, n = sim_vs_bare(desc, a.sim_seconds)
    rows.append((f"MjcfSim advance + state, {n} steps (best of 3)", *node, ""))
    rows.append((f"bare mj_step, same model, {n} steps (best of 3)", *bare, ""))
    print(f"mjcf plant, 7-joint arm, {ds.n} samples ({a.seconds:g} s at {a.rate:g} Hz); "
          f"top: {d.ranking[0].effect}")
    print(f"| {'step':<55} | {'wall s':>7} | {'CPU s':>7} | {'target':<8} |")
    print(f"| {'-' * 55} | {'-' * 7} | {'-' * 7} | {'-' * 8} |")
    for name, wall, cpu, target in rows:
        print(f"| {name:<55} | {wall:7.2f} | {cpu:7.2f} | {target:<8} |")
    ratio_wall, ratio_cpu = node[0] / bare[0], node[1] / max(bare[1], 1e-9)
    print(f"| {'ratio simulator / bare mj_step':<55} | {ratio_wall:6.2f}x | {ratio_cpu:6.2f}x | {'<= 3x':<8} |")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
