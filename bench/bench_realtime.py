"""Real time on an ordinary machine: offline CDPR simulation vs bare mj_step, the machine's floor,
the 1 kHz control loop in one process and the 1 kHz loop of three node processes over DDS,
in one run, by default without real-time privileges (``--rt-priority``: all of them under
SCHED_FIFO alike).

1. Offline: ``simulate`` (MuJoCo 2 ms physics, PDFF + live estimator at 100 Hz) of the 60 s test
   trajectory with 615 kg, and a bare loop of ``mujoco.mj_step`` on the simulator's own MjModel
   (one call per physics step, nothing else; ``ctrl`` holds the static feedforward torques of the
   start pose so the cables carry the platform as in the run), the same simulated time, in this
   one run. Each is the best wall time of ``--repeat`` alternating tries (the machine may be
   shared). Target: ``realtime_factor`` >= 1/3 of ``bare_mj_step_realtime_factor``.
2. Three-process loop (JSON key ``three_process``): ``cable_sim_node --plant cdpr`` in
   real-time mode at 1000 Hz, ``payload_estimator`` and ``pd_feedforward`` as three processes
   over DDS (own ROS_DOMAIN_ID from ``cablelab.ros.launch``), normal scheduling (``rt_priority``
   0), ``--seconds`` s of steady state (the measuring code is ``bench_cdpr.run_closed_loop``).
   Targets: ``realtime_factor`` >= 0.99, ``missed_cycles`` <= 3x the C rcl pair's (steps braked
   for want of a command, run a period or more late, or applying a command that answers an
   older state, each step counted once, plus steps dropped when too far behind), every in-node
   p99 < 1 ms (the worst 1 s window of each node).
3. The floor, in the same run (``bench_rcl_floor.py``'s code, ``bench/rcl_floor/floor.c`` built
   with ``$CC``, default ``cc``; reported as unavailable, not failed, without a C compiler): the
   bare timer (a C process sleeping to absolute 1 ms deadlines, nothing else) and the C rcl
   simulator/controller pair, ``--seconds`` each.
4. The control loop (``control_loop --plant cdpr``: the simulated CDPR and the PDFF law in one
   process on absolute deadlines, docs/nodes.md) at 1 kHz with ``payload_estimator`` as a
   second process, ``--seconds`` after a 1 s warm-up. Its cycles are counted as the bare
   timer's (a wake-up a period or more late, plus periods skipped more than 20 behind);
   ``p99_ms`` is the loop body's (read -> law -> write) p99 in the worst 1 s window. Targets:
   ``missed_cycles`` <= 2x the bare timer's, ``p99_ms`` < 0.5.
Parts 2-4 at 1 kHz run in ``--segments`` alternating segments (default 3 of ``--seconds``/3:
bare timer, C pair, control loop, three processes, then again), so that background load that comes
and goes over minutes meets the floor and the loops alike; each figure is summed over the segments
(counts, seconds), the largest (p99s, maxima) or their mean (realtime factors, CPU per step), and
each ``missed_cycles`` comes with ``segment_missed``, the count of each segment.
5. A rate sweep: the bare timer and the control loop at 100, 250, 500 Hz (``--sweep-seconds``
   each; the 1000 Hz row is parts 3-4), printed beside the floor.

``--json`` prints one JSON object::

    {"offline_sim": {"plant": "cdpr", "realtime_factor", "bare_mj_step_realtime_factor"},
     "floor": {"bare_timer_missed", "c_rcl_pair_missed", "seconds", "available", "rt_priority"},
     "control_loop": {"rate_hz": 1000, "seconds", "missed_cycles", "late", "dropped", "p99_ms",
                      "realtime_factor", "cpu_per_cycle_ms" (the loop's process), "wakeup_max_ms",
                      "publisher", "publisher_cpu_per_cycle_ms" (its publisher process),
                      "samples_lost", "rt_priority", "placement"},
     "three_process": {"rate_hz": 1000, "seconds", "realtime_factor", "missed_cycles", "segment_missed",
                       "braked", "late", "stale", "dropped", "segments": [those counts of each segment],
                       "p99_ms": {"sim", "estimator", "controller"}, "rt_priority": false,
                       "threads": {node: {thread name: {"cpu_us", "wait_us", "runs"} per step}},
                       "slow_publishes" (the controller's compiled path: publishes > 0.2 ms),
                       "sim_slow_publishes" (the simulator's compiled path: joint-state, tension,
                       reference publishes > 0.2 ms), "sim_publish_max_ms", "sim_wake_max_ms", ...},
     "rate_sweep": [{"rate_hz", "bare_timer_missed", "control_loop_missed", "p99_ms",
                     "realtime_factor", "seconds"}, ...]}

Run it on a quiet machine: ``./run python bench/bench_realtime.py --seconds 60 --json`` (the
10-minute soak: ``--seconds 600 --segments 1``). ``--py-spy PATH`` samples the three node processes with
py-spy and prints each one's share of samples by innermost function (where the time goes);
``--publication-mode asynchronous`` runs the nodes with Fast DDS asynchronous publishing.
Placement without privileges: ``--idle-estimator`` (the estimator in the SCHED_IDLE class),
``--idle-python`` (the three-process simulator's and controller's Python threads in it once their
compiled threads run; node parameter ``python_idle``),
``--pin`` (that, plus simulator and estimator on CPU 0, controller on CPU 1), ``--node-params
JSON`` (any node parameters, e.g. ``'{"sim": {"sched_slice": 0.0001}}'``); the JSON's
``placement`` says what was used; ``--loop-params JSON`` the control loop's (e.g. ``'{"loop":
{"publisher": "thread"}}'``). ``--rt-priority PRIO`` runs the bare timer and the C rcl pair
(``chrt -f PRIO``), the control loop's process (not its publisher process, nor the estimator)
and the three-process simulator and controller (node parameter ``rt_priority``) under SCHED_FIFO
PRIO, so that the ratios compare like with like (needs the privilege).
"""
from __future__ import annotations

import json
import sys
import tempfile
import time
from pathlib import Path


sys.path.insert(0, str(Path(__file__).resolve().parent))
from harness import Bench, table  # noqa: E402
from realtime_runs import IDLE_ESTIMATOR, cdpr_hold, closed_loop, merge_segments  # noqa: E402


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


#: ``--pin`` for the control loop: the loop on the CPU of the three-process controller, the
#: estimator (off the deadline path) on the other in the SCHED_IDLE class
LOOP_PINNED = {"loop": {"cpu_affinity": [1]}, "estimator": {"cpu_affinity": [0], "sched_idle": True}}

SWEEP_RATES = (100.0, 250.0, 500.0)


def build_floor(log):
    """(floor executable, MJB, state file) of ``bench/rcl_floor/floor.c``, or the one-line reason
    why not (no C compiler, no shared libpython)."""
    from bench_rcl_floor import build, model_files

    tmp = Path(tempfile.mkdtemp(prefix="bench-rt-floor-"))
    try:
        exe = build(tmp)
    except SystemExit as exc:
        log(f"floor unavailable: {exc}")
        return None, str(exc)
    mjb, state = model_files(tmp)
    return (exe, mjb, state), None


def floor(built, seconds: float, log, pin: bool = False, rt: int = 0) -> dict:
    """The bare timer and the C rcl pair at 1 kHz, ``seconds`` each (bench_rcl_floor), under
    SCHED_FIFO ``rt`` if > 0."""
    from bench_rcl_floor import run_floor, run_timer

    exe, mjb, state = built
    log(f"floor: bare timer, {seconds:g} s ...")
    timer = run_timer(exe, seconds, pin, rt)
    log(f"floor: rcl loop in C, {seconds:g} s ...")
    pair = run_floor(exe, mjb, state, seconds, False, pin, log, rt)
    return {"available": True, "seconds": seconds, "bare_timer_missed": timer["missed_cycles"],
            "c_rcl_pair_missed": pair["missed_cycles"], "rt_priority": rt > 0, "bare_timer": timer,
            "c_rcl_pair": pair}


def control_loop(seconds: float, log, rate: float = 1000.0, pin: bool = False, extra: dict | None = None) -> dict:
    """``control_loop --plant cdpr`` at ``rate`` Hz with ``payload_estimator`` (batch mode, 100 Hz)
    as a second process, ``seconds`` after the loop's 1 s warm-up; the figures are the loop's own
    summary line (:meth:`cablelab.ros.control_loop.ControlLoopNode.summary`)."""
    from cablelab.ros.launch import Launcher

    placement = {k: dict(v) for k, v in (LOOP_PINNED if pin else IDLE_ESTIMATOR).items()}
    for k, v in (extra or {}).items():
        placement.setdefault(k, {}).update(v)
    tmp = Path(tempfile.mkdtemp(prefix="bench-rt-loop-"))
    with Launcher(log_dir=tmp / "logs") as launch:
        log(f"control loop {rate:g} Hz, {seconds:g} s: ROS_DOMAIN_ID {launch.domain_id}, logs in {launch.log_dir}")
        launch.node("estimator", "payload_estimator", "cdpr", {"poll_period": 0.01} | placement.get("estimator", {}))
        launch.wait_for_topics({"/diagnostics": 1}, timeout=60)       # the estimator is up
        params = {"rate": rate, "duration": seconds + 1.0, "warmup": 1.0, "payload_mass": 249.0,
                  "extras_every": max(1, int(round(rate / 100.0)))} | placement.get("loop", {})
        argv = [sys.executable, "-m", "pd_feedforward.control_loop", "--plant", "cdpr", "--ros-args"]
        for k, v in params.items():
            argv += ["-p", f"{k}:={v}"]
        proc = launch.start("loop", argv)
        code = proc.wait(20 * seconds + 120)
        launch.stop_all()
        lines = [ln for ln in proc.log().splitlines() if ln.startswith('{"node": "control_loop"')]
    if code != 0 or not lines:
        raise SystemExit(f"bench_realtime: the control loop failed (exit {code}); log {proc.log_path}:\n"
                         + proc.log()[-1500:])
    r = json.loads(lines[-1])
    return {"rate_hz": rate, "seconds": r["cycles"] / rate, "missed_cycles": r["missed_cycles"],
            "late": r["late"], "dropped": r["dropped"], "cycles": r["cycles"], "p99_ms": r["p99_ms"],
            "p99_all_ms": r["p99_all_ms"], "median_ms": r["median_ms"],
            "realtime_factor": r["realtime_factor"], "cpu_per_cycle_ms": r.get("cpu_per_cycle_ms"),
            "wakeup_max_ms": r.get("wakeup_max_ms"), "publisher": r.get("publisher"),
            "publisher_cpu_per_cycle_ms": r.get("publisher_cpu_per_cycle_ms"),
            "samples_lost": r.get("samples_lost"),
            "rt_priority": int(placement.get("loop", {}).get("rt_priority", 0)) > 0, "placement": placement or None}


def _thread_rows(prefix: str, threads: dict) -> list:
    """Table rows of bench_cdpr's per-thread readings (threads under 1 us CPU per step left out)."""
    return [dict(case=f"{prefix}{node} thread {name}: CPU / run-queue wait per step, runs per step",
                 value=f"{v['cpu_us']:.1f} / {v['wait_us']:.1f} us, {v['runs']:.2f}", unit="", target="")
            for node, rows in threads.items() for name, v in rows.items() if v["cpu_us"] >= 1.0]


def _segments(d: dict) -> str:
    """`` (segments a + b + c)`` of a merged result, or nothing for one segment."""
    seg = d.get("segment_missed") or []
    return f" (segments {' + '.join(map(str, seg))})" if len(seg) > 1 else ""


def _fmt(x, digits: int = 4) -> str:
    return "-" if x is None else f"{x:.{digits}f}"


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
    bench.parser.add_argument("--idle-python", action="store_true",
                              help="the three-process simulator's and controller's Python threads in SCHED_IDLE "
                                   "once their compiled paths run (node parameter python_idle; otherwise nice 10)")
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
    bench.parser.add_argument("--skip-floor", action="store_true", help="no bare timer / C rcl pair")
    bench.parser.add_argument("--skip-control-loop", action="store_true", help="no control_loop process")
    bench.parser.add_argument("--skip-three-process", action="store_true", help="no three-process loop")
    bench.parser.add_argument("--skip-sweep", action="store_true", help="no rate sweep")
    bench.parser.add_argument("--loop-params", default=None, metavar="JSON",
                              help='extra parameters of the control-loop runs\' processes, e.g. '
                                   '\'{"loop": {"publish_thread": true}}\' (keys loop, estimator)')
    bench.parser.add_argument("--rt-priority", type=int, default=0, metavar="PRIO",
                              help="SCHED_FIFO at PRIO (needs the privilege) for the bare timer, the C rcl "
                                   "pair, the control loop's process (not its publisher process nor the "
                                   "estimator) and the three-process simulator and controller (0: off)")
    bench.parser.add_argument("--segments", type=int, default=3,
                              help="run each 1 kHz measurement (bare timer, C rcl pair, control loop, three "
                                   "processes) as this many alternating segments of --seconds/N, summed (3)")
    bench.parser.add_argument("--sweep-seconds", type=float, default=20.0,
                              help="s per rate of the sweep's 100, 250, 500 Hz runs (20)")
    args = bench.parse(argv)
    out = {}
    if not args.skip_offline:
        bench.log("offline simulation vs bare mj_step ...")
        out["offline_sim"] = offline_sim(repeat=args.repeat)
    built = None
    loop_extra = json.loads(args.loop_params) if args.loop_params else None
    rt = max(0, args.rt_priority)
    if rt:
        loop_extra = loop_extra or {}
        loop_extra.setdefault("loop", {}).setdefault("rt_priority", rt)
    if not args.skip_loop and not (args.skip_floor and args.skip_sweep):
        built, why = build_floor(bench.log)
        if built is None:
            out["floor"] = {"available": False, "reason": why, "bare_timer_missed": None, "c_rcl_pair_missed": None}
    run_floor = not args.skip_loop and not args.skip_floor and built is not None
    run_loop = not args.skip_loop and not args.skip_control_loop
    run_three = not args.skip_loop and not args.skip_three_process
    env, extra = {}, json.loads(args.node_params) if args.node_params else {}
    if args.publication_mode:
        env["RMW_FASTRTPS_PUBLICATION_MODE"] = args.publication_mode.upper()
    if args.transports:
        env["FASTDDS_BUILTIN_TRANSPORTS"] = args.transports
    for name in ("sim", "controller") if args.idle_python else ():
        extra.setdefault(name, {}).setdefault("python_idle", True)
    for name in ("sim", "controller") if rt else ():
        extra.setdefault(name, {}).setdefault("rt_priority", rt)
    # the 1 kHz measurements in alternating segments: a minute of background load meets all alike
    segments = max(1, args.segments)
    seg = args.seconds / segments
    parts = {"floor": [], "control_loop": [], "three_process": []}
    for i in range(segments if run_floor or run_loop or run_three else 0):
        if segments > 1:
            bench.log(f"segment {i + 1} of {segments}: {seg:g} s of each 1 kHz measurement")
        if run_floor:
            parts["floor"].append(floor(built, seg, bench.log, args.pin, rt))
        if run_loop:
            parts["control_loop"].append(control_loop(seg, bench.log, 1000.0, args.pin, loop_extra))
        if run_three:
            # (its steady state starts at the simulator's first report after 1 s: one more second)
            parts["three_process"].append(closed_loop(seg + (segments > 1), bench.log, env, args.py_spy, args.pin,
                                                      extra or None, args.idle_estimator))
    if parts["floor"]:
        out["floor"] = merge_segments(parts["floor"])
    if parts["control_loop"]:
        out["control_loop"] = merge_segments(parts["control_loop"])
    if not args.skip_loop and not args.skip_sweep:
        from bench_rcl_floor import run_timer

        sweep = []
        for rate in SWEEP_RATES:
            row = {"rate_hz": rate, "seconds": args.sweep_seconds, "bare_timer_missed": None}
            if built is not None:
                bench.log(f"sweep: bare timer {rate:g} Hz, {args.sweep_seconds:g} s ...")
                row["bare_timer_missed"] = run_timer(built[0], args.sweep_seconds, args.pin, rt, rate)["missed_cycles"]
            c = control_loop(args.sweep_seconds, bench.log, rate, args.pin, loop_extra)
            row.update(control_loop_missed=c["missed_cycles"], p99_ms=c["p99_ms"], realtime_factor=c["realtime_factor"])
            sweep.append(row)
        f, c = out.get("floor", {}), out.get("control_loop")
        if c is not None:
            sweep.append({"rate_hz": 1000.0, "seconds": args.seconds, "bare_timer_missed": f.get("bare_timer_missed"),
                          "control_loop_missed": c["missed_cycles"], "p99_ms": c["p99_ms"],
                          "realtime_factor": c["realtime_factor"]})
        out["rate_sweep"] = sweep
    if parts["three_process"]:
        r = merge_segments(parts["three_process"])
        out["three_process"] = {"rate_hz": r["rate_hz"], "seconds": r["seconds"],
                                "realtime_factor": r["realtime_factor"], "missed_cycles": r["missed_cycles"],
                                "segment_missed": r.get("segment_missed", [r["missed_cycles"]]),
                                **{k: r[k] for k in ("braked", "late", "stale", "dropped")},
                                "segments": [{k: p[k] for k in ("missed_cycles", "braked", "late", "stale", "dropped",
                                                                "realtime_factor")} for p in parts["three_process"]],
                                "p99_ms": r["p99_ms"], "rt_priority": r["rt_priority"],
                                "command_age_steps": r["command_age"], "placement": r["placement"],
                                "cpu_ms": r["cpu_ms"], "threads": r.get("threads", {}),
                                "slow_publishes": r.get("slow_publishes"),
                                **{k: r.get(k) for k in ("sim_slow_publishes", "sim_publish_max_ms", "sim_wake_max_ms")}}
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
    if "floor" in out:
        f = out["floor"]
        if not f["available"]:
            rows.append(dict(case="floor (bare timer, C rcl pair)", value="unavailable: " + f["reason"].splitlines()[0],
                             unit="", target=""))
        else:
            fifo = ", SCHED_FIFO" if f.get("rt_priority") else ""
            rows += [dict(case=f"floor: bare timer 1 kHz{fifo}, {f['seconds']:.0f} s (missed = late + dropped)",
                          value=f"{f['bare_timer_missed']}{_segments(f['bare_timer'])} "
                                f"(wake-up p99 {f['bare_timer']['p99_ms']['wake-up']:.3f} ms)",
                          unit=f"of {int(round(f['bare_timer']['seconds'] * 1000))}", target=""),
                     dict(case="floor: C rcl simulator/controller pair 1 kHz",
                          value=f"{f['c_rcl_pair_missed']}{_segments(f['c_rcl_pair'])}",
                          unit=f"of {int(round(f['c_rcl_pair']['seconds'] * 1000))}", target="")]
            rows.append(dict(case="floor: C rcl pair's command / state publishes over 0.2 ms",
                             value=f"{f['c_rcl_pair'].get('slow_publishes', '-')} / "
                                   f"{f['c_rcl_pair'].get('slow_state_publishes', '-')}", unit="", target=""))
            rows += _thread_rows("C pair ", f["c_rcl_pair"].get("threads", {}))
    if "control_loop" in out:
        c = out["control_loop"]
        bare = out.get("floor", {}).get("bare_timer_missed")
        prio = ", SCHED_FIFO" if c.get("rt_priority") else ""
        rows += [dict(case=f"control loop 1 kHz (control_loop + estimator, publisher {c.get('publisher')}{prio}), "
                           f"{c['seconds']:.0f} s: missed cycles "
                           f"(late {c['late']} + dropped {c['dropped']})",
                      value=f"{c['missed_cycles']}{_segments(c)}", unit=f"of {c['cycles'] + c['dropped']}",
                      target=f"<= {2 * bare} (2x bare timer)" if bare is not None else "<= 2x bare timer"),
                 dict(case="control loop body p99 (read -> law -> write, worst 1 s window) / median",
                      value=f"{c['p99_ms']:.3f} / {c['median_ms']:.3f}", unit="ms", target="< 0.5"),
                 dict(case="control loop realtime factor / CPU per cycle (all threads)",
                      value=f"{_fmt(c['realtime_factor'])} / {_fmt(c['cpu_per_cycle_ms'], 3)}",
                      unit="x / ms", target="")]
    if "three_process" in out:
        c = out["three_process"]
        where = ("sim + estimator (SCHED_IDLE) on CPU 0, controller on CPU 1" if args.pin else
                 "estimator SCHED_IDLE, no CPU placement" if args.idle_estimator else "no CPU placement")
        if args.idle_python:
            where += ", simulator's and controller's Python threads SCHED_IDLE"
        if args.node_params:
            where += f", node parameters {args.node_params}"
        prio = "SCHED_FIFO (node parameter rt_priority)" if c["rt_priority"] else "no RT priority"
        pair = out.get("floor", {}).get("c_rcl_pair_missed")
        rows += [dict(case=f"closed loop 1 kHz, 3 processes, {prio}, {where}, {c['seconds']:.0f} s steady state",
                      value=c["realtime_factor"], unit="x real time", target=">= 0.99"),
                 dict(case="missed cycles (steps braked, late or with a stale command, + dropped)",
                      value=f"{c['missed_cycles']}{_segments(c)} (braked {r['braked']}, late {r['late']}, "
                            f"dropped {r['dropped']}, stale {r['stale']})",
                      unit=f"of {r['steps']}", target=f"<= {3 * pair} (3x C rcl pair)" if pair is not None
                      else "<= 3x C rcl pair")]
        rows.append(dict(case="applied command answers the state 1 / 2 / >= 3 periods back",
                         value=" / ".join(str(a) for a in r["command_age"]), unit="steps", target=""))
        rows += [dict(case=f"in-node p99, {k} (worst 1 s window)", value=v, unit="ms", target="< 1")
                 for k, v in c["p99_ms"].items()]
        rows.append(dict(case="CPU per step sim / estimator / controller",
                         value=" / ".join(f"{v:.3f}" for v in r["cpu_ms"].values()), unit="ms", target=""))
        rows.append(dict(case="load average before / after", value=" / ".join(r["load"]), unit="", target=""))
        rows.append(dict(case="controller's compiled path: command publishes over 0.2 ms (held up inside DDS)",
                         value="-" if c["slow_publishes"] is None else c["slow_publishes"],
                         unit=f"of {r['steps']}", target=""))
        if c.get("sim_slow_publishes") is not None:
            rows.append(dict(case="simulator's compiled path: joint-state / tension / reference publishes over 0.2 ms; "
                                  "slowest publish, latest wake-up (ms)",
                             value=" / ".join(map(str, c["sim_slow_publishes"]))
                             + f"; {c['sim_publish_max_ms']:.3f}, {c['sim_wake_max_ms']:.3f}",
                             unit=f"of {r['steps']}", target=""))
        rows += _thread_rows("", c["threads"])
    print(table(rows))
    if out.get("rate_sweep"):
        print()
        print(table([dict(rate_hz=f"{r['rate_hz']:g}", seconds=f"{r['seconds']:g}",
                          bare_timer_missed="-" if r["bare_timer_missed"] is None else r["bare_timer_missed"],
                          control_loop_missed=r["control_loop_missed"], loop_body_p99_ms=f"{r['p99_ms']:.3f}",
                          realtime_factor=_fmt(r["realtime_factor"])) for r in out["rate_sweep"]]))
    return 0


if __name__ == "__main__":
    sys.exit(main())
