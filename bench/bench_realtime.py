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
   ``missed_cycles`` 0 (steps braked for want of a command, run a period or more late, or
   applying a command that answers an older state, each step counted once, plus steps dropped
   when too far behind), every in-node p99
   < 1 ms (the worst 1 s window of each node).

``--json`` prints one JSON object::

    {"offline_sim": {"plant": "cdpr", "realtime_factor", "bare_mj_step_realtime_factor"},
     "closed_loop": {"rate_hz": 1000, "seconds", "realtime_factor", "missed_cycles",
                     "p99_ms": {"sim", "estimator", "controller"}, "rt_priority": false}}

Run it on a quiet machine: ``./run python bench/bench_realtime.py --seconds 60 --json`` (the
10-minute soak: ``--seconds 600``). ``--py-spy PATH`` samples the three node processes with
py-spy and prints each one's share of samples by innermost function (where the time goes);
``--publication-mode asynchronous`` runs the nodes with Fast DDS asynchronous publishing.
Placement without privileges: ``--idle-estimator`` (the estimator in the SCHED_IDLE class),
``--pin`` (that, plus simulator and estimator on CPU 0, controller on CPU 1), ``--node-params
JSON`` (any node parameters, e.g. ``'{"sim": {"sched_slice": 0.0001}}'``); the JSON's
``placement`` says what was used.
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


def cdpr_hold(timestep: float = 0.002):
    """The CDPR simulator at the start pose of the test trajectory (615 kg) and the winch torques
    (N m) that hold it there statically (eq. 14 feedforward at rest): ``(CdprSim, hold)``."""
    from cablelab.plants.cdpr.control import feedforward_tensions
    from cablelab.plants.cdpr.geometry import cable_geometry
    from cablelab.plants.cdpr.sim import CdprSim, CdprTruth, default_description
    from cablelab.plants.cdpr.trajectory import sample_trajectory

    desc = default_description()
    c = desc.cdpr
    start = sample_trajectory(1.0, 100.0).position[0]
    sim = CdprSim(desc, CdprTruth(payload_mass=249.0, timestep=timestep), start)
    g = cable_geometry(c.exit_points, c.anchor_points, start[None], None, sim.truth.pulley_radius, c.swivel_axes)
    hold = (c.drum_radius / c.gear_ratio) * feedforward_tensions(g, sim.truth.total_mass, np.zeros((1, 3)),
                                                                  desc.gravity)[0]
    return sim, hold


def offline_sim(duration: float = 60.0, repeat: int = 3) -> dict:
    """Best-of-``repeat`` real-time factors of ``simulate`` and of bare mj_step on its model."""
    import mujoco

    from cablelab.plants.cdpr.sim import CdprTruth, simulate

    sim, hold = cdpr_hold()
    desc, truth, start = sim.desc, CdprTruth(payload_mass=sim.truth.payload_mass), sim.position
    model, data = sim.model, sim.data
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


def _py_spy_profiles(py_spy: str, out_dir: Path, seconds: float, log):
    """``on_started`` hook: sample each node with py-spy for ``seconds`` (from 3 s after start,
    past the start-up) into ``out_dir/<node>.txt`` (collapsed stacks, raw format)."""
    import subprocess

    procs = []

    def start(pids):
        for name, pid in pids.items():
            procs.append((name, subprocess.Popen(
                ["sh", "-c", f"sleep 3; exec {py_spy} record --nonblocking -r 250 -d {int(seconds)} "
                             f"--pid {pid} -f raw -o {out_dir / (name + '.txt')}"],
                stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)))
        log(f"py-spy: sampling {', '.join(pids)} for {int(seconds)} s into {out_dir}")

    return start, procs


def profile_summary(path: Path, top: int = 8) -> list[tuple[str, float]]:
    """Share of the samples per innermost Python function of a py-spy raw profile."""
    from collections import Counter

    leaf, total = Counter(), 0
    for line in path.read_text().splitlines():
        stack, _, n = line.rpartition(" ")
        if not stack:
            continue
        total += int(n)
        leaf[stack.split(";")[-1].split(" (")[0]] += int(n)
    return [(f, n / max(total, 1)) for f, n in leaf.most_common(top)]


#: ``--pin``: the placement a 2-core deployment gives the loop without privileges: the simulator
#: and the controller on a core each, the estimator (off the state -> command path) beside the
#: simulator in the SCHED_IDLE class, so that it only takes what the simulator leaves
PINNED = {"sim": {"cpu_affinity": [0]}, "controller": {"cpu_affinity": [1]},
          "estimator": {"cpu_affinity": [0], "sched_idle": True}}

#: ``--idle-estimator``: the estimator (off the state -> command path, its output low-pass
#: filtered by the controller) in the SCHED_IDLE class, no CPU placement
IDLE_ESTIMATOR = {"estimator": {"sched_idle": True}}


def closed_loop(seconds: float, log, env: dict | None = None, py_spy: str | None = None,
                pin: bool = False, extra: dict | None = None, idle_estimator: bool = False,
                controller_argv: list | None = None) -> dict:
    from bench_cdpr import run_closed_loop

    from cablelab.ros.launch import Launcher

    tmp = Path(tempfile.mkdtemp(prefix="bench-rt-"))
    hook, spies = (None, [])
    if py_spy:
        hook, spies = _py_spy_profiles(py_spy, tmp, max(1.0, min(seconds - 3.0, 30.0)), log)
    with Launcher(log_dir=tmp / "logs", env=env) as launch:
        log(f"ROS_DOMAIN_ID {launch.domain_id}, logs in {launch.log_dir}")
        placement = {k: dict(v) for k, v in (PINNED if pin else IDLE_ESTIMATOR if idle_estimator else {}).items()}
        for k, v in (extra or {}).items():
            placement.setdefault(k, {}).update(v)
        r = run_closed_loop(launch, seconds, {}, log, on_started=hook, node_params=placement or None,
                            controller_argv=controller_argv)
    for name, proc in spies:
        proc.wait(timeout=60)
        f = tmp / f"{name}.txt"
        if f.exists():
            log(f"py-spy {name} (share of samples by innermost function): " +
                ", ".join(f"{fn} {100 * x:.0f} %" for fn, x in profile_summary(f)))
    if r is None:
        raise SystemExit("bench_realtime: the simulator never reported on /diagnostics (see the logs)")
    r["rate_hz"] = 1000
    r["rt_priority"] = any(int(v.get("rt_priority", 0)) > 0 for v in placement.values())
    r["placement"] = placement or None
    return r


def main(argv=None) -> int:
    bench = Bench("realtime", __doc__)
    bench.parser.add_argument("--seconds", type=float, default=60.0, help="closed-loop steady state, s (60)")
    bench.parser.add_argument("--repeat", type=int, default=3, help="offline tries, best of (3)")
    bench.parser.add_argument("--skip-loop", action="store_true", help="offline part only")
    bench.parser.add_argument("--pin", action="store_true",
                              help="place the nodes (no privilege): sim and estimator (SCHED_IDLE) on CPU 0, "
                                   "controller on CPU 1 (needs >= 2 CPUs)")
    bench.parser.add_argument("--idle-estimator", action="store_true",
                              help="run the estimator in the SCHED_IDLE class (no privilege; no CPU placement)")
    bench.parser.add_argument("--node-params", default=None, metavar="JSON",
                              help='extra node parameters, e.g. \'{"sim": {"sched_slice": 0.0001}}\'')
    bench.parser.add_argument("--skip-offline", action="store_true", help="closed loop only")
    bench.parser.add_argument("--publication-mode", choices=("synchronous", "asynchronous"), default=None,
                              help="RMW_FASTRTPS_PUBLICATION_MODE for the three nodes (default: rmw's)")
    bench.parser.add_argument("--transports", default=None, metavar="T",
                              help="FASTDDS_BUILTIN_TRANSPORTS for the three nodes (e.g. SHM, UDPv4, "
                                   "DEFAULT); default: what cablelab.ros.launch sets")
    bench.parser.add_argument("--py-spy", default=None, metavar="PATH",
                              help="py-spy executable: sample each node and print where its time goes")
    args = bench.parse(argv)
    out = {}
    if not args.skip_offline:
        bench.log("offline simulation vs bare mj_step ...")
        out["offline_sim"] = offline_sim(repeat=args.repeat)
    if not args.skip_loop:
        env = {}
        if args.publication_mode:
            env["RMW_FASTRTPS_PUBLICATION_MODE"] = args.publication_mode.upper()
        if args.transports:
            env["FASTDDS_BUILTIN_TRANSPORTS"] = args.transports
        r = closed_loop(args.seconds, bench.log, env, args.py_spy, args.pin,
                        json.loads(args.node_params) if args.node_params else None, args.idle_estimator)
        out["closed_loop"] = {"rate_hz": r["rate_hz"], "seconds": r["seconds"],
                              "realtime_factor": r["realtime_factor"], "missed_cycles": r["missed_cycles"],
                              "p99_ms": r["p99_ms"], "rt_priority": r["rt_priority"],
                              "command_age_steps": r["command_age"], "placement": r["placement"]}
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
        where = ("sim + estimator (SCHED_IDLE) on CPU 0, controller on CPU 1" if args.pin else
                 "estimator SCHED_IDLE, no CPU placement" if args.idle_estimator else "no CPU placement")
        if args.node_params:
            where += f", node parameters {args.node_params}"
        prio = "SCHED_FIFO (node parameter rt_priority)" if c["rt_priority"] else "no RT priority"
        rows += [dict(case=f"closed loop 1 kHz, 3 processes, {prio}, {where}, {c['seconds']:.0f} s steady state",
                      value=c["realtime_factor"], unit="x real time", target=">= 0.99"),
                 dict(case="missed cycles (steps braked, late or with a stale command, + dropped)",
                      value=f"{c['missed_cycles']} (braked {r['braked']}, late {r['late']}, "
                            f"dropped {r['dropped']}, stale {r['stale']})",
                      unit=f"of {r['steps']}", target="0")]
        rows.append(dict(case="applied command answers the state 1 / 2 / >= 3 periods back",
                         value=" / ".join(str(a) for a in r["command_age"]), unit="steps", target=""))
        rows += [dict(case=f"in-node p99, {k} (worst 1 s window)", value=v, unit="ms", target="< 1")
                 for k, v in c["p99_ms"].items()]
        rows.append(dict(case="CPU per step sim / estimator / controller",
                         value=" / ".join(f"{v:.3f}" for v in r["cpu_ms"].values()), unit="ms", target=""))
        rows.append(dict(case="load average before / after", value=" / ".join(r["load"]), unit="", target=""))
    print(table(rows))
    return 0


if __name__ == "__main__":
    sys.exit(main())
