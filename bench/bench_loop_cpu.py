"""Where the CDPR control loop's CPU goes in one period, with the law prepared per period and
with it planned in blocks, in one run.

The work of one period of ``control_loop --plant cdpr`` without the sleep and without ROS:
``hardware.read()`` (the simulated winch sensors), ``law.update(state)`` (the PDFF law),
``hardware.write(command)`` (one period of MuJoCo physics), ``law.prepare_next(t)`` (the
reference terms of the next period) and the record copied into the publisher's shared-memory
ring (``StateLayout.pack``), each timed with the thread's CPU clock over ``--periods`` untimed
periods, a live estimate fed every 10 periods as the loop takes them. Two laws on the same
simulated robot: ``per_period`` (:class:`~cablelab.plants.cdpr.loop.ReferenceLaw` without a
reference grid: :meth:`LiveController.prepare` once per period, as the ``pd_feedforward`` node
does) and ``planned`` (with the reference table's grid, as the loop runs: the reference terms of
64 periods at once, :meth:`LiveController.plan`, and :meth:`LiveController.planned_law` per
period). The two alternate ``--repeat`` times; each part's figure is its least mean over the
repeats (the machine may be shared); ``prepare_next_max`` is the longest single
``prepare_next`` (planned: one block at once). Hot caches: a loop that sleeps between periods pays more
(``bench_realtime.py``'s ``cpu_per_cycle_ms`` is the loop's process in real time).

    ./run python bench/bench_loop_cpu.py [--periods 5000] [--repeat 3] [--json]
"""
from __future__ import annotations

import argparse
import json
import time

import numpy as np

PARTS = ("read", "law", "write", "prepare_next", "pack")


def _one(planned: bool, periods: int) -> dict:
    from cablelab.plants.cdpr.hardware import SimulatedCdpr
    from cablelab.plants.cdpr.live import ControllerConfig, LiveController
    from cablelab.plants.cdpr.loop import ReferenceLaw
    from cablelab.plants.cdpr.sim import CdprTruth, default_description
    from cablelab.plants.cdpr.trajectory import ReferenceTable
    from cablelab.sample_ring import StateLayout

    rate = 1000.0
    desc = default_description()
    ref = ReferenceTable(rate, 0.5, 1.0)
    hw = SimulatedCdpr(desc, CdprTruth(payload_mass=250.0, timestep=0.001), rate, ref.at(0.0)[0])
    ctl = LiveController(desc.cdpr, desc.gravity, ControllerConfig())
    law = ReferenceLaw(ctl, ref.at, ref.rows, rate) if planned else ReferenceLaw(ctl, ref.at)
    hw.start()
    state = hw.read()
    layout = StateLayout.of(state)
    row = np.empty(layout.width)
    spent = dict.fromkeys(PARTS, 0.0)
    most = 0.0                             # the longest prepare_next (a block planned at once)
    clock = time.thread_time
    for k in range(periods + 200):
        if k == 200:                       # warm-up done: count from here
            spent, most = dict.fromkeys(PARTS, 0.0), 0.0
        c0 = clock()
        state = hw.read()
        c1 = clock()
        command = law.update(state)
        c2 = clock()
        hw.write(command)
        c3 = clock()
        if k % 10 == 5:                    # the estimator's 100 Hz (not timed: the loop's rclpy take)
            law.estimate(state.t, 616.0, (0.01, -0.02))
        c4 = clock()
        law.prepare_next(state.t + 1.0 / rate)
        c5 = clock()
        layout.pack(row, state, command)
        c6 = clock()
        for part, dt in zip(PARTS, (c1 - c0, c2 - c1, c3 - c2, c5 - c4, c6 - c5)):
            spent[part] += dt
        most = max(most, c5 - c4)
    out = {part: 1e3 * s / periods for part, s in spent.items()}
    out["total"] = sum(out.values())
    out["prepare_next_max"] = 1e3 * most
    return out


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0],
                                 formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--periods", type=int, default=5000, help="periods timed per try")
    ap.add_argument("--repeat", type=int, default=3, help="alternating tries of each law")
    ap.add_argument("--json", action="store_true", help="one JSON object instead of the table")
    a = ap.parse_args(argv)
    best: dict = {}
    for _ in range(a.repeat):
        for name in ("per_period", "planned"):
            got = _one(name == "planned", a.periods)
            prev = best.get(name)
            best[name] = got if prev is None else {k: min(v, prev[k]) for k, v in got.items()}
    best["periods"], best["repeat"] = a.periods, a.repeat
    if a.json:
        print(json.dumps(best))
        return 0
    print(f"CPU ms per period (thread CPU, least mean of {a.repeat} tries of {a.periods} periods)")
    print(f"{'part':14s} {'per_period':>11s} {'planned':>9s}")
    for part in (*PARTS, "total", "prepare_next_max"):
        print(f"{part:14s} {best['per_period'][part]:11.4f} {best['planned'][part]:9.4f}")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
