"""The floor under the 1 kHz closed loop: how many cycles does the lightest ROS 2 stack
miss on this machine, without real-time privileges, and how many does the machine itself miss?

First the bare timer: one process sleeping to absolute 1 ms deadlines (``clock_nanosleep``) with
nothing to do; a wake-up a period or more late is a cycle no program on this machine could have
kept (``--rt-timer PRIO``: the same under SCHED_FIFO, if the privilege is there).

``bench/rcl_floor/floor.c`` is a simulator and a controller written against rcl in C (no Python,
no executor; the same Fast DDS over shared memory, the same ``cablelab.ros.launch`` domain and
environment as the nodes). The simulator holds the CDPR of ``bench_realtime`` at its start pose
with one ``mj_step`` of the node's own MjModel (1 ms physics) per 1 ms period, at absolute
deadlines, and publishes 8-winch joint states and 8 tensions each period; the controller answers
each state with an 8-value command naming its stamp. Missed cycles are counted as
``bench_realtime`` counts them (a step woken a period or more late, or whose newest command does
not answer the last published state, plus steps dropped more than 20 periods behind; after the
first second). ``--listener`` adds a third process: rclpy subscribing to both state topics with
the default executor (the load a Python estimator puts on the machine).

Then, in the same run, ``--compare`` runs the cablelab nodes (``bench_realtime``'s closed loop,
same seconds, same placement) so that the two are measured side by side, and ``--mixed`` the
cablelab simulator and estimator answered by the C controller (which holds the first state's
torques instead of tracking: a timing measurement, not control), to split the misses between the
Python simulator and the Python controller.

Builds with the C compiler in ``$CC`` (default ``cc``) against the headers and libraries of the
installed ros-jazzy and MuJoCo wheels and libpython (the wheels' rmw libraries refer to it). A
machine with Python only can use the ``ziglang`` wheel (0.17.0 tried):
``CC="$PWD/.venv/bin/python -m ziglang cc"`` with ziglang on the venv's path.

    ./run python bench/bench_rcl_floor.py --seconds 60 [--listener] [--pin] [--compare] [--rt-timer 50] [--json]
"""
from __future__ import annotations

import json
import os
import shlex
import shutil
import subprocess
import sys
import sysconfig
import tempfile
import time
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parent))
from harness import Bench, table  # noqa: E402

HERE = Path(__file__).resolve().parent
SOURCE = HERE / "rcl_floor" / "floor.c"
LIBS = ["rcl", "rmw", "rcutils", "rosidl_runtime_c", "sensor_msgs__rosidl_typesupport_c",
        "sensor_msgs__rosidl_generator_c", "std_msgs__rosidl_typesupport_c",
        "std_msgs__rosidl_generator_c", "builtin_interfaces__rosidl_generator_c"]


def python_link() -> list[str]:
    """Linker flags for libpython: the wheels' rmw libraries carry Python bindings that refer to
    its symbols (a C program must load it too)."""
    libdir, ver = sysconfig.get_config_var("LIBDIR"), sysconfig.get_config_var("LDVERSION")
    if not sysconfig.get_config_var("Py_ENABLE_SHARED"):
        raise SystemExit("bench_rcl_floor: this Python has no shared libpython, which the ros-jazzy "
                         "wheels' libraries need in a C program")
    return [f"-L{libdir}", "-Wl,--no-as-needed", f"-lpython{ver}", "-Wl,--as-needed", f"-Wl,-rpath,{libdir}"]


def build(out_dir: Path) -> Path:
    """Compile floor.c into ``out_dir``; one-line SystemExit if there is no compiler."""
    import mujoco

    venv = Path(sys.prefix)
    inc = [f"-I{p}" for p in sorted((venv / "include").iterdir()) if p.is_dir()]
    mj = Path(mujoco.__file__).parent
    mjlib = next(mj.glob("libmujoco.so*"))
    exe = out_dir / "floor"
    cc = shlex.split(os.environ.get("CC", "cc"))
    cmd = [*cc, "-O2", "-o", str(exe), str(SOURCE), *inc, f"-I{mj / 'include'}",
           f"-L{venv / 'lib'}", "-Wl,--allow-shlib-undefined", *[f"-l{x}" for x in LIBS],
           str(mjlib), f"-Wl,-rpath,{mj}", *python_link(), "-lm"]
    try:
        r = subprocess.run(cmd, capture_output=True, text=True)
    except FileNotFoundError:
        raise SystemExit(f"bench_rcl_floor: no C compiler '{cc[0]}': install one or set CC "
                         "(e.g. CC=\"$PWD/.venv/bin/python -m ziglang cc\" with the ziglang wheel)") from None
    if r.returncode:
        raise SystemExit(f"bench_rcl_floor: compiling {SOURCE} failed:\n{r.stderr[-2000:]}")
    return exe


def model_files(out_dir: Path) -> tuple[Path, Path]:
    """The simulator's MjModel at 1 kHz (1 ms physics) holding the start pose, as MJB + state."""
    import mujoco

    from realtime_runs import cdpr_hold

    sim, hold = cdpr_hold(timestep=0.001)
    mjb, state = out_dir / "cdpr.mjb", out_dir / "state.txt"
    mujoco.mj_saveModel(sim.model, str(mjb), None)
    d = sim.data
    state.write_text("\n".join(" ".join(repr(float(v)) for v in a) for a in (d.qpos, d.qvel, hold)) + "\n")
    return mjb, state


LISTENER = """
import rclpy, sys
from rclpy.node import Node
from sensor_msgs.msg import JointState
from std_msgs.msg import Float64MultiArray
from rclpy.qos import QoSProfile, ReliabilityPolicy
rclpy.init()
n = Node("floor_listener")
q = QoSProfile(depth=100, reliability=ReliabilityPolicy.RELIABLE)
count = [0]
def cb(_m):
    count[0] += 1
n.create_subscription(JointState, "/floor/joint_states", cb, q)
n.create_subscription(Float64MultiArray, "/floor/cable_tensions", cb, q)
try:
    rclpy.spin(n)
except BaseException:
    pass
print(count[0], flush=True)
"""

PIN = {"sim": [0], "ctrl": [1], "listener": [0]}


def run_floor(exe: Path, mjb: Path, state: Path, seconds: float, listener: bool, pin: bool, log,
              rt: int = 0) -> dict:
    from cablelab.ros.launch import Launcher

    tmp = Path(tempfile.mkdtemp(prefix="bench-floor-"))
    with Launcher(log_dir=tmp / "logs") as launch:
        log(f"ROS_DOMAIN_ID {launch.domain_id}, logs in {launch.log_dir}")
        procs = {}

        def placed(name, argv):   # taskset: every thread of the process on that CPU; chrt: SCHED_FIFO
            return ((["chrt", "-f", str(rt)] if rt > 0 and name != "listener" else [])
                    + (["taskset", "-c", ",".join(map(str, PIN[name]))] if pin else []) + argv)
        if pin and not shutil.which("taskset"):
            raise SystemExit("bench_rcl_floor: --pin needs taskset (util-linux)")
        if listener:
            procs["listener"] = launch.start("listener", placed("listener", [sys.executable, "-c", LISTENER]))
        procs["ctrl"] = launch.start("ctrl", placed("ctrl", [str(exe), "ctrl"]))
        time.sleep(1.0)
        procs["sim"] = launch.start("sim", placed("sim", [str(exe), "sim", str(mjb), str(state),
                                                          str(seconds + 1.0), "1000"]))
        threads = _sample_threads({"sim": procs["sim"].popen.pid, "controller": procs["ctrl"].popen.pid},
                                  2.0, seconds - 1.0)
        assert procs["sim"].wait(seconds + 120) == 0, procs["sim"].log()[-2000:]
        assert procs["ctrl"].wait(30) == 0, procs["ctrl"].log()[-2000:]
        launch.stop_all()
        out = {}
        for name in ("sim", "ctrl"):
            lines = [ln for ln in procs[name].log().splitlines() if ln.startswith("{")]
            out[name] = json.loads(lines[-1])
    sim, ctrl = out["sim"], out["ctrl"]
    return {"rate_hz": 1000, "seconds": sim["steps"] / 1000.0, "realtime_factor": sim["realtime_factor"],
            "missed_cycles": sim["missed_cycles"], "late": sim["late"], "stale": sim["stale"],
            "dropped": sim["dropped"], "p99_ms": {"sim": sim["p99_ms"], "controller": ctrl["p99_ms"]},
            "cpu_per_step_ms": {"sim": sim["cpu_per_step_ms"], "controller": ctrl["cpu_per_answer_ms"]},
            "listener": listener, "pinned": pin, "rt_priority": rt > 0, "threads": threads,
            "slow_publishes": ctrl.get("slow_publishes"), "slow_state_publishes": sim.get("slow_state_publishes")}


def _sample_threads(pids: dict, first: float, last: float) -> dict:
    """Per-thread CPU, run-queue wait and runs per 1 ms step of each process in ``pids``
    (bench_cdpr's /proc readings) between ``first`` and ``last`` s from now ({} if a process
    ended before)."""
    from bench_cdpr import _thread_deltas, _threads

    try:
        time.sleep(first)
        before = {k: _threads(p) for k, p in pids.items()}
        time.sleep(last - first)
        after = {k: _threads(p) for k, p in pids.items()}
    except OSError:
        return {}
    return _thread_deltas(before, after, round((last - first) * 1000))


def run_timer(exe: Path, seconds: float, pin: bool, rt: int, rate: float = 1000.0) -> dict:
    """The bare timer: the same absolute deadlines (1 ms at ``rate`` 1000 Hz) with nothing to do
    (no ROS, no physics), on CPU 0 with --pin; ``rt`` > 0 runs it under SCHED_FIFO (chrt, needs
    the privilege)."""
    argv = [str(exe), "timer", str(seconds + 1.0), f"{rate:g}"]
    if rt > 0:
        argv = ["chrt", "-f", str(rt), *argv]
    if pin:
        argv = ["taskset", "-c", ",".join(map(str, PIN["sim"])), *argv]
    r = subprocess.run(argv, capture_output=True, text=True)   # (no ROS: ./run's library path only)
    if r.returncode:
        raise SystemExit(f"bench_rcl_floor: the bare timer failed: {r.stderr.strip()[-500:]}")
    t = json.loads(r.stdout.strip().splitlines()[-1])
    return {"rate_hz": rate, "seconds": t["steps"] / rate, "realtime_factor": None,
            "missed_cycles": t["missed_cycles"], "late": t["late"], "stale": 0, "dropped": t["dropped"],
            "p99_ms": {"wake-up": t["wakeup_p99_ms"]}, "wakeup_max_ms": t["wakeup_max_ms"],
            "pinned": pin, "rt_priority": rt > 0}


def main(argv=None) -> int:
    bench = Bench("rcl_floor", __doc__)
    p = bench.parser
    p.add_argument("--seconds", type=float, default=60.0, help="steady state, s (60)")
    p.add_argument("--listener", action="store_true", help="a third process: an rclpy subscriber of both state topics")
    p.add_argument("--pin", action="store_true", help="sim (and listener) on CPU 0, controller on CPU 1")
    p.add_argument("--compare", action="store_true", help="then the cablelab nodes (bench_realtime's loop), same seconds")
    p.add_argument("--mixed", action="store_true",
                   help="then the cablelab simulator and estimator answered by the C controller (holding "
                        "the start torques): how much of the loop's misses the Python controller adds")
    p.add_argument("--timers-only", action="store_true", help="only the bare timer(s): the machine's floor")
    p.add_argument("--rt-timer", type=int, default=0, metavar="PRIO",
                   help="also the bare timer under SCHED_FIFO PRIO (chrt; needs the privilege)")
    args = bench.parse(argv)
    log = bench.log
    tmp = Path(tempfile.mkdtemp(prefix="bench-floor-build-"))
    exe = build(tmp)
    mjb, state = model_files(tmp)
    log(f"bare timer, {args.seconds:g} s ...")
    result = {"bare timer": run_timer(exe, args.seconds, args.pin, 0)}
    if args.rt_timer:
        log(f"bare timer under SCHED_FIFO {args.rt_timer}, {args.seconds:g} s ...")
        result["bare timer, SCHED_FIFO"] = run_timer(exe, args.seconds, args.pin, args.rt_timer)
    if not args.timers_only:
        log(f"rcl loop in C, {args.seconds:g} s ...")
        result["rcl loop in C"] = run_floor(exe, mjb, state, args.seconds, args.listener, args.pin, log)
    if args.compare or args.mixed:
        from realtime_runs import closed_loop
    if args.compare:
        log(f"cablelab nodes, {args.seconds:g} s ...")
        result["cablelab nodes"] = closed_loop(args.seconds, log, pin=args.pin)
    if args.mixed:
        log(f"cablelab simulator and estimator with the C controller, {args.seconds:g} s ...")
        argv = (["taskset", "-c", ",".join(map(str, PIN["ctrl"]))] if args.pin else []) + \
            [str(exe), "ctrl", "/cdpr/joint_states", "/cdpr/effort_commands"]
        result["cablelab sim + C controller"] = closed_loop(args.seconds, log, pin=args.pin, controller_argv=argv)
    if args.json:
        print(json.dumps(result))
        return 0
    rows = []
    for name, r in result.items():
        rows.append(dict(loop=name, realtime=f"{r['realtime_factor']:.4f}" if r["realtime_factor"] is not None else "",
                         missed=f"{r['missed_cycles']} of {int(round(r['seconds'] * 1000))}",
                         late_stale_dropped=f"{r['late']} / {r['stale']} / {r['dropped']}",
                         p99_ms=" / ".join(f"{k} {v:.3f}" for k, v in r["p99_ms"].items()),
                         cpu_ms=" / ".join(f"{k} {v:.3f}" for k, v in
                                           (r.get("cpu_per_step_ms") or r.get("cpu_ms") or {}).items())))
    print(table(rows))
    return 0


if __name__ == "__main__":
    sys.exit(main())
