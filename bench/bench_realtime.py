"""Real time on an ordinary machine (issue 14): offline CDPR simulation vs bare mj_step, and the
1 kHz closed loop of three node processes over DDS without real-time privileges.

1. Offline: ``simulate`` (MuJoCo 2 ms physics, PDFF + live estimator at 100 Hz) of the 60 s test
   trajectory with 615 kg, and a bare loop of ``mujoco.mj_step`` on the simulator's own MjModel
   (one call per physics step, nothing else; ``ctrl`` holds the static feedforward torques of the
   start pose so the cables carry the platform as in the run), the same simulated time, in this
   one run. Each is the best wall time of ``--repeat`` alternating tries (the machine may be
   shared). Target: ``realtime_factor`` >= 1/3 of ``bare_mj_step_realtime_factor``.
2. Closed loop: ``cable_sim_node --plant cdpr`` in real-time mode at 1000 Hz, ``payload_estimator``
   and ``pd_feedforward`` as three processes over DDS (own ROS_DOMAIN_ID from
   ``cablelab.ros.launch``), normal scheduling (``rt_priority`` 0), ``--seconds`` s of steady state
   (the measuring code is ``bench_cdpr.run_closed_loop``). Targets: ``realtime_factor`` >= 0.99,
   ``missed_cycles`` 0 (steps braked for want of a command, run a period or more late, dropped
   when too far behind, or applying a command that answers an older state), every in-node p99
   < 1 ms (the worst 1 s window of each node).

``--json`` prints one JSON object::

    {"offline_sim": {"plant": "cdpr", "realtime_factor", "bare_mj_step_realtime_factor"},
     "closed_loop": {"rate_hz": 1000, "seconds", "realtime_factor", "missed_cycles",
                     "p99_ms": {"sim", "estimator", "controller"}, "rt_priority": false}}

Run it on a quiet machine: ``./run python bench/bench_realtime.py --seconds 60 --json`` (the
10-minute soak: ``--seconds 600``).
"""
from __future__ import annotations

import json
import sys
import tempfile
import time
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parent))
from harness import Bench, table  # noqa: E402


def offline_sim(duration: float = 60.0, repeat: int = 3) -> dict:
    """Best-of-``repeat`` real-time factors of ``simulate`` and of bare mj_step on its model."""
    import mujoco

    from cablelab.plants.cdpr.control import feedforward_tensions
    from cablelab.plants.cdpr.geometry import cable_geometry
    from cablelab.plants.cdpr.sim import CdprSim, CdprTruth, default_description, simulate
    from cablelab.plants.cdpr.trajectory import sample_trajectory

    desc = default_description()
    c = desc.cdpr
    truth = CdprTruth(payload_mass=249.0)
    start = sample_trajectory(1.0, 100.0).position[0]
    sim = CdprSim(desc, truth, start)
    model, data = sim.model, sim.data
    g = cable_geometry(c.exit_points, c.anchor_points, start[None], None, sim.truth.pulley_radius, c.swivel_axes)
    hold = (c.drum_radius / c.gear_ratio) * feedforward_tensions(g, sim.truth.total_mass, np.zeros((1, 3)),
                                                                  desc.gravity)[0]
    nsteps = int(round(duration / model.opt.timestep))
    best_sim = best_bare = float("inf")
    for _ in range(repeat):
        sim.reset(start)
        data.ctrl[:] = hold
        step = mujoco.mj_step
        t0 = time.perf_counter()
        for _ in range(nsteps):
            step(model, data)
        best_bare = min(best_bare, time.perf_counter() - t0)
        t0 = time.perf_counter()
        simulate(desc, truth, controller="pdff", duration=duration)
        best_sim = min(best_sim, time.perf_counter() - t0)
    return {"plant": "cdpr", "realtime_factor": duration / best_sim,
            "bare_mj_step_realtime_factor": duration / best_bare}


def closed_loop(seconds: float, log) -> dict:
    from bench_cdpr import run_closed_loop

    from cablelab.ros.launch import Launcher

    tmp = Path(tempfile.mkdtemp(prefix="bench-rt-"))
    with Launcher(log_dir=tmp / "logs") as launch:
        log(f"ROS_DOMAIN_ID {launch.domain_id}, logs in {launch.log_dir}")
        r = run_closed_loop(launch, seconds, {}, log)
    if r is None:
        raise SystemExit("bench_realtime: the simulator never reported on /diagnostics (see the logs)")
    r["rate_hz"] = 1000
    r["rt_priority"] = False
    return r


def main(argv=None) -> int:
    bench = Bench("realtime", __doc__)
    bench.parser.add_argument("--seconds", type=float, default=60.0, help="closed-loop steady state, s (60)")
    bench.parser.add_argument("--repeat", type=int, default=3, help="offline tries, best of (3)")
    bench.parser.add_argument("--skip-loop", action="store_true", help="offline part only")
    bench.parser.add_argument("--skip-offline", action="store_true", help="closed loop only")
    args = bench.parse(argv)
    out = {}
    if not args.skip_offline:
        bench.log("offline simulation vs bare mj_step ...")
        out["offline_sim"] = offline_sim(repeat=args.repeat)
    if not args.skip_loop:
        r = closed_loop(args.seconds, bench.log)
        out["closed_loop"] = {"rate_hz": r["rate_hz"], "seconds": r["seconds"],
                              "realtime_factor": r["realtime_factor"], "missed_cycles": r["missed_cycles"],
                              "p99_ms": r["p99_ms"], "rt_priority": r["rt_priority"]}
    if args.json:
        print(json.dumps(out))
        return 0
    rows = []
    if "offline_sim" in out:
        o = out["offline_sim"]
        rows += [dict(case="offline simulate(), 60 s, 615 kg (PDFF + live estimator 100 Hz)",
                      value=o["realtime_factor"], unit="x real time", target=""),
                 dict(case="bare mj_step loop, same MjModel, same simulated time",
                      value=o["bare_mj_step_realtime_factor"], unit="x real time", target=""),
                 dict(case="ratio bare / simulate", value=o["bare_mj_step_realtime_factor"] / o["realtime_factor"],
                      unit="", target="<= 3")]
    if "closed_loop" in out:
        c = out["closed_loop"]
        rows += [dict(case=f"closed loop 1 kHz, 3 processes, no RT priority, {c['seconds']:.0f} s steady state",
                      value=c["realtime_factor"], unit="x real time", target=">= 0.99"),
                 dict(case="missed cycles (braked + late + dropped + stale command)",
                      value=f"{c['missed_cycles']} ({r['braked']} + {r['late']} + {r['dropped']} + {r['stale']})",
                      unit=f"of {r['steps']}", target="0")]
        rows += [dict(case=f"in-node p99, {k} (worst 1 s window)", value=v, unit="ms", target="< 1")
                 for k, v in c["p99_ms"].items()]
        rows.append(dict(case="CPU per step sim / estimator / controller",
                         value=" / ".join(f"{v:.3f}" for v in r["cpu_ms"].values()), unit="ms", target=""))
        rows.append(dict(case="load average before / after", value=" / ".join(r["load"]), unit="", target=""))
    print(table(rows))
    return 0


if __name__ == "__main__":
    sys.exit(main())
