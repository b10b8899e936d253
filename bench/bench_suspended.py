"""Speed of the suspended plant: CRANEbot simulation vs real time, the LiCAS
7-experiment identification, and the live swing estimator per pose sample.

    ./run python bench/bench_suspended.py [--json] [--full]

Rows: ``sim`` = CRANEbot virtual-joint model, 60 s simulated through
:func:`cablelab.plants.suspended.sim.simulate` (mujoco.rollout) against a bare ``mj_step`` loop
on the same model (ratio = overhead); ``identify`` = Pearson then NMSE fit of the 7 LiCAS
experiments (3 identification, 4 validation; ``--full``: all 21 Table 5 (★) parameters instead of
the 7 the tests use); ``estimator`` = :class:`SwingEstimator.step` per sample (p50, p99) against
the bare batch formula on one sample; ``p99_us`` is wall time (includes preemption on a loaded
machine), ``p99_cpu_us`` the thread CPU time of the same calls.
"""
from __future__ import annotations

import sys
import time
from pathlib import Path

import mujoco
import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parent))
from harness import Bench  # noqa: E402

from cablelab.plants.suspended.identify import IDENTIFIED, identify, licas_experiments, validate  # noqa: E402
from cablelab.plants.suspended.mjcf import build_virtual  # noqa: E402
from cablelab.plants.suspended.params import parameter_set  # noqa: E402
from cablelab.plants.suspended.sim import STATE_SPEC, initial_state, simulate  # noqa: E402
from cablelab.plants.suspended.swing import SwingEstimator, swing_angles  # noqa: E402


def main() -> None:
    bench = Bench("suspended", __doc__)
    bench.parser.add_argument("--full", action="store_true", help="identify all 21 Table 5 parameters")
    args = bench.parse()

    # ---------------------------------------------------------------- CRANEbot simulation
    p = parameter_set("cranebot")
    m = build_virtual(p)
    x0 = initial_state(m, {"J9": 0.05, "J7": 0.2})
    T = 60.0
    wall = bench.time(lambda: simulate(m, x0, T), repeat=3)
    d = mujoco.MjData(m)

    def bare():
        mujoco.mj_setState(m, d, x0, STATE_SPEC)
        for _ in range(int(T / m.opt.timestep)):
            mujoco.mj_step(m, d)

    wall_bare = bench.time(bare, repeat=3)
    bench.row(case="sim cranebot (rollout)", simulated_s=T, wall_s=wall, real_time_x=T / wall,
              vs_bare_mj_step=wall / wall_bare, target=">= 50x real time")
    bench.row(case="sim cranebot (bare mj_step)", simulated_s=T, wall_s=wall_bare, real_time_x=T / wall_bare)

    # ---------------------------------------------------------------- identification
    bench.section("identify")
    pl = parameter_set("licas")
    names = [r[0] for r in IDENTIFIED] if args.full else ["l9z", "kp7", "kp10", "kd10", "fv7", "fv8", "fv9"]
    t0 = time.perf_counter()
    ide, val = licas_experiments(pl, duration=6.0, seed=3)
    pear = identify(ide, pl, names, objective="pearson", max_iter=8)
    nm = identify(ide, pl, names, objective="nmse", start=pear.values, max_iter=6)
    rows = validate(nm.params, val)
    dt = time.perf_counter() - t0
    rho = min(float(np.min(r["rho"][r["use"]])) for r in rows)
    mre = max(float(np.max(r["mre"][r["use"]])) for r in rows)
    bench.row(case=f"licas 7 experiments, {len(names)} params", wall_s=dt, mean_R=pear.mean_R,
              min_val_rho=rho, max_val_mre=mre, rollouts=pear.fit.evaluations + nm.fit.evaluations,
              target="< 120 s")

    # ---------------------------------------------------------------- live estimator
    bench.section("estimator")
    n = 20000
    t = np.arange(n) * 0.01
    pos = np.array(pl.S) + 1.0 * np.stack([0.1 * np.sin(t), 0.1 * np.cos(t), -np.ones(n)], 1)
    quat = np.stack([np.cos(0.1 * t), 0 * t, 0 * t, np.sin(0.1 * t)], 1)
    est = SwingEstimator(pl.S, rest_window=2.0)
    lat = np.empty(n)
    cpu = np.empty(n)
    for i in range(n):
        a, c = time.perf_counter(), time.thread_time()
        est.step(t[i], pos[i], quat[i])
        lat[i] = time.perf_counter() - a
        cpu[i] = time.thread_time() - c
    bare_lat = np.empty(n)
    for i in range(n):
        a = time.perf_counter()
        swing_angles(pos[i], pl.S)
        bare_lat[i] = time.perf_counter() - a
    bench.row(case="SwingEstimator.step", samples=n, p50_us=1e6 * np.percentile(lat, 50),
              p99_us=1e6 * np.percentile(lat, 99), p99_cpu_us=1e6 * np.percentile(cpu, 99),
              vs_bare_p50=np.percentile(lat, 50) / np.percentile(bare_lat, 50),
              target="p99 < 1000 us")
    bench.row(case="bare swing_angles (one sample)", samples=n, p50_us=1e6 * np.percentile(bare_lat, 50),
              p99_us=1e6 * np.percentile(bare_lat, 99))
    bench.done()


if __name__ == "__main__":
    main()
