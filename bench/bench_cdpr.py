"""CDPR benchmarks (speed targets).

1. Offline estimation, Model I and Model II (001 eq. 6-9, 12-13), --samples samples of 8 cables
   on one core (``mass_com_batch``; the general ``cable_geometry + mass_com`` path for reference).
   Target: Model II >= 1 000 000 samples/s.
2. Offline closed-loop simulation (MuJoCo 2 ms physics, PDFF + live estimator at 100 Hz) of the
   60 s test trajectory. Target: >= 20x real time.
3. Estimator node in its own process fed at 1 kHz over DDS (/cdpr/cable_tensions +
   /cdpr/reference, --seconds s): estimates received vs sent, processing latency p99 (measured in
   the node, reported on /diagnostics) and end-to-end latency. Target: p99 < 1 ms, zero drops.
4. Closed loop sim -> estimator -> controller -> sim at 1 kHz in real-time mode (three
   processes, --seconds s): achieved rate, commands per state, steps the simulator had to brake
   because no fresh command came.

``--paper`` instead prints the reproduction of 001 Tables I-II and Fig. 15 (three payloads, PD and
PDFF runs of the offline simulation) used in src/cablelab/cablelab/plants/cdpr/README.md.
"""
from __future__ import annotations

import sys
import tempfile
import time
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parent))
from harness import Bench  # noqa: E402


def offline_estimation(bench: Bench, samples: int) -> None:
    from cablelab.plants.cdpr.estimation import mass_com, mass_com_batch
    from cablelab.plants.cdpr.geometry import cable_geometry
    from cablelab.plants.cdpr.trajectory import pick_and_place
    from cablelab.plants.cdpr.sim import default_description

    bench.section(f"offline estimation, {samples} samples x 8 cables, one core")
    c = default_description().cdpr
    P = pick_and_place(np.linspace(0.0, 60.0, samples)).position
    T = np.random.default_rng(0).uniform(500.0, 2000.0, (samples, 8))
    for r, name in ((0.0, "Model I"), (0.15, "Model II")):
        best = bench.time(lambda: mass_com_batch(c.exit_points, c.anchor_points, P, T, r), repeat=3)
        bench.row(case=f"{name} mass + CoM (mass_com_batch)", samples=samples, seconds=best,
                  rate=samples / best, unit="samples/s",
                  target=">= 1 000 000" if r else "")
    n = min(samples, 200_000)
    best = bench.time(lambda: mass_com(cable_geometry(c.exit_points, c.anchor_points, P[:n], None, 0.15),
                                       T[:n]), repeat=2)
    bench.row(case="Model II, general path (cable_geometry + mass_com)", samples=n, seconds=best,
              rate=n / best, unit="samples/s", target="")


def offline_simulation(bench: Bench) -> None:
    from cablelab.plants.cdpr.sim import CdprTruth, default_description, simulate

    bench.section("offline closed-loop simulation (60 s test trajectory, 615 kg)")
    desc = default_description()
    t0 = time.perf_counter()
    run = simulate(desc, CdprTruth(payload_mass=249.0), controller="pdff", duration=60.0)
    el = time.perf_counter() - t0
    bench.row(case="MuJoCo 500 Hz physics + PDFF/estimator 100 Hz", simulated_s=60.0, seconds=el,
              rate=60.0 / el, unit="x real time", target=">= 20")
    ez = np.abs(run.true_position[:, 2] - run.ref_position[:, 2]).max()
    bench.log(f"  (max |z error| {1000 * ez:.2f} mm, mean live mass {np.nanmean(run.est_mass):.1f} kg)")


def estimator_in_process(bench: Bench, n: int = 5000) -> None:
    """Per-sample cost of the estimator node's callbacks (reference + tensions), called directly
    with ready messages: the compute part of the latency, without DDS and scheduling."""
    import rclpy

    from cablelab.plants.cdpr.control import feedforward_tensions
    from cablelab.plants.cdpr.geometry import cable_geometry
    from cablelab.plants.cdpr.trajectory import pick_and_place
    from cablelab.ros import convert
    from cablelab.plants.cdpr.sim import default_description
    from cablelab.plants.cdpr.nodes.estimator import CdprPayloadEstimator
    from cablelab.plants.cdpr.nodes.controller import CdprController

    bench.section("node callbacks in process (compute only: no DDS, no executor)")
    desc = default_description()
    c = desc.cdpr
    tr = pick_and_place(np.arange(n) * 1e-3)
    T = feedforward_tensions(cable_geometry(c.exit_points, c.anchor_points, tr.position, None, 0.15),
                             615.0, np.zeros((n, 3)))
    names = [f"cable_{i}" for i in range(1, 9)]
    refs = [convert.multidof_msg(k * 1e-3, tr.position[k], [0, 0, 0, 1.0], tr.velocity[k], None,
                                 tr.acceleration[k], None) for k in range(n)]
    tens = [convert.joint_state_msg(k * 1e-3, names, None, None, T[k]) for k in range(n)]
    js = [convert.joint_state_msg(k * 1e-3, [f"winch_{i}" for i in range(1, 9)], -666 * np.ones(8),
                                  np.zeros(8), np.ones(8)) for k in range(n)]
    rclpy.init(domain_id=231)
    try:
        est = CdprPayloadEstimator()
        ctl = CdprController()
        est.pub.publish = lambda m: None
        ctl.pub_cmd.publish = lambda m: None
        est.on_description(convert.string_msg(desc.to_yaml()))
        ctl.on_description(convert.string_msg(desc.to_yaml()))
        for name, fn in (("estimator: reference + tensions callbacks", lambda k: (est.on_reference(refs[k]),
                                                                                  est.on_tensions(tens[k]))),
                         ("controller: reference + joint_states callbacks", lambda k: (ctl.on_reference(refs[k]),
                                                                                       ctl.on_state(js[k])))):
            dt = np.empty(n)
            for k in range(n):
                t0 = time.perf_counter()
                fn(k)
                dt[k] = time.perf_counter() - t0
            bench.row(case=name, samples=n, median_ms=1000 * float(np.median(dt)),
                      p99_ms=1000 * float(np.quantile(dt, 0.99)), target="p99 < 1 ms")
        est.destroy_node()
        ctl.destroy_node()
    finally:
        rclpy.try_shutdown()


def _cpu_seconds(pid: int) -> float:
    """User + system CPU time (s) used so far by process ``pid`` and its threads (Linux /proc)."""
    import os

    fields = open(f"/proc/{pid}/stat").read().rsplit(")", 1)[1].split()
    return (int(fields[11]) + int(fields[12])) / os.sysconf("SC_CLK_TCK")


def _threads(pid: int) -> dict:
    """{thread name: [CPU ns, run-queue wait ns, times scheduled]} of process ``pid``, summed over
    its threads of one name (Linux /proc/PID/task/TID/schedstat; Fast DDS names its threads
    ``dds.*``, the compiled paths theirs ``sim_path`` and ``controller_path``)."""
    import os
    import re

    out = {}
    for tid in os.listdir(f"/proc/{pid}/task"):
        try:
            comm = open(f"/proc/{pid}/task/{tid}/comm").read().strip()
            run, wait, slices = (int(x) for x in open(f"/proc/{pid}/task/{tid}/schedstat").read().split()[:3])
        except (OSError, ValueError):
            continue
        acc = out.setdefault(re.sub(r"[.-]?\d+$", "", comm), [0, 0, 0])
        acc[0] += run
        acc[1] += wait
        acc[2] += slices
    return out


def _thread_deltas(before: dict, after: dict, steps: int) -> dict:
    """{node: {thread: {"cpu_us", "wait_us", "runs"} per step}} between two :func:`_threads`
    readings of each node, threads using the most CPU first."""
    out = {}
    for node, b in before.items():
        rows = {}
        for name, (run, wait, n) in after.get(node, {}).items():
            r0, w0, n0 = b.get(name, (0, 0, 0))
            rows[name] = {"cpu_us": (run - r0) / 1e3 / steps, "wait_us": (wait - w0) / 1e3 / steps,
                          "runs": (n - n0) / steps}
        out[node] = dict(sorted(rows.items(), key=lambda kv: -kv[1]["cpu_us"]))
    return out


def _load() -> str:
    import os

    return "/".join(f"{x:.1f}" for x in os.getloadavg())


class _Client:
    """A plain rclpy node in this process on the launcher's domain."""

    def __init__(self, domain_id: int):
        import rclpy
        from rclpy.context import Context
        from rclpy.executors import SingleThreadedExecutor
        from rclpy.node import Node

        self.ctx = Context()
        rclpy.init(context=self.ctx, domain_id=domain_id)
        self.node = Node("bench_cdpr", context=self.ctx)
        self.ex = SingleThreadedExecutor(context=self.ctx)
        self.ex.add_node(self.node)
        self.diag = {}

        from diagnostic_msgs.msg import DiagnosticArray
        self.node.create_subscription(DiagnosticArray, "/diagnostics", self._on_diag, 50)

    def _on_diag(self, msg) -> None:
        for st in msg.status:
            self.diag[st.name] = {kv.key: kv.value for kv in st.values} | {"_message": st.message}

    def spin(self, seconds: float) -> None:
        end = time.monotonic() + seconds
        while time.monotonic() < end:
            self.ex.spin_once(timeout_sec=0.01)

    def close(self) -> None:
        import rclpy

        self.node.destroy_node()
        rclpy.try_shutdown(context=self.ctx)


def estimator_node(bench: Bench, launch, seconds: float, params: dict) -> None:
    from geometry_msgs.msg import InertiaStamped
    from sensor_msgs.msg import JointState
    from std_msgs.msg import String
    from trajectory_msgs.msg import MultiDOFJointTrajectory

    from cablelab.plants.cdpr.control import feedforward_tensions
    from cablelab.plants.cdpr.geometry import cable_geometry
    from cablelab.plants.cdpr.trajectory import pick_and_place
    from cablelab.ros import convert
    from cablelab.ros.qos import DESCRIPTION_QOS, stream_qos
    from cablelab.plants.cdpr.sim import default_description

    bench.section(f"estimator node at 1 kHz for {seconds:g} s (separate process, DDS)")
    desc = default_description()
    c = desc.cdpr
    launch.node("estimator", "payload_estimator", "cdpr", params)
    cl = _Client(launch.domain_id)
    q = stream_qos(1000)
    pub_d = cl.node.create_publisher(String, "/plant_description", DESCRIPTION_QOS)
    pub_r = cl.node.create_publisher(MultiDOFJointTrajectory, "/cdpr/reference", q)
    pub_t = cl.node.create_publisher(JointState, "/cdpr/cable_tensions", q)
    recv = {}
    cl.node.create_subscription(InertiaStamped, "/cdpr/payload_estimate",
                                lambda m: recv.setdefault(round(convert.from_stamp(m.header.stamp) * 1000),
                                                          time.perf_counter()), q)
    pub_d.publish(convert.string_msg(desc.to_yaml()))
    deadline = time.monotonic() + 60
    while time.monotonic() < deadline and not (pub_t.get_subscription_count() and
                                               pub_r.get_subscription_count() and "payload_estimator" in cl.diag):
        cl.spin(0.1)
    cl.spin(1.0)
    n = int(seconds * 1000)
    tr = pick_and_place(np.arange(n) * 1e-3)
    geom = cable_geometry(c.exit_points, c.anchor_points, tr.position, None, 0.15)
    T = feedforward_tensions(geom, 615.0, np.zeros((n, 3)))
    names = [f"cable_{i}" for i in range(1, 9)]
    sent = {}
    pid = launch.procs["estimator"].popen.pid
    cpu0 = _cpu_seconds(pid)
    load0 = _load()
    t0 = time.monotonic()
    k = 0
    while k < n:
        due = min(n, int((time.monotonic() - t0) * 1000) + 1)
        while k < due:
            t = k * 1e-3
            pub_r.publish(convert.multidof_msg(t, tr.position[k], [0, 0, 0, 1.0], tr.velocity[k], None,
                                               tr.acceleration[k], None))
            pub_t.publish(convert.joint_state_msg(t, names, None, None, T[k]))
            sent[k] = time.perf_counter()
            k += 1
        cl.ex.spin_once(timeout_sec=0.0005)
        if k % 5000 == 0 and k:
            bench.log(f"  sent {k}/{n}, ETA {max(0.0, seconds - (time.monotonic() - t0)):.0f} s")
    elapsed = time.monotonic() - t0
    cl.spin(3.0)
    cpu = _cpu_seconds(pid) - cpu0
    lat = np.array([recv[k] - sent[k] for k in recv if k in sent]) * 1e3
    d = cl.diag.get("payload_estimator", {})
    bench.row(case="estimator node: estimates / tension samples", sent=n, received=len(recv),
              dropped=n - len(recv), rate_hz=n / elapsed, target="zero drops")
    bench.row(case="estimator processing latency p99 (in node)", value=d.get("latency p99 ms", "?"),
              unit="ms", target="< 1 ms")
    bench.row(case="end-to-end latency publish -> estimate received", value=float(np.median(lat)),
              p99=float(np.quantile(lat, 0.99)), unit="ms (median, p99)", target="")
    bench.row(case="estimator process CPU per sample (all its threads)", value=1000 * cpu / n, unit="ms",
              target="")
    bench.log(f"  load average before/after: {load0} / {_load()}")
    cl.close()
    launch.stop("estimator")


def run_closed_loop(launch, seconds: float, params: dict, log=print, on_started=None,
                    node_params: dict | None = None, controller_argv: list | None = None) -> dict | None:
    """Three node processes (estimator, controller, simulator in real-time mode at 1 kHz) on the
    launcher's domain for ``seconds`` of simulated time; measured from the simulator's and the
    nodes' own /diagnostics (1 Hz) and /proc CPU times, over the steady state (from 1 s of sim time,
    start-up and DDS discovery excluded). None when the simulator never reported.

    Returns the steady-state figures: ``realtime_factor`` (sim time / wall time), ``steps``,
    ``commands_per_state``, ``braked`` (steps without a fresh command after the first one),
    ``late`` / ``dropped`` / ``stale`` (steps run a period or more late, dropped when too far
    behind, applying a command that answers an older state), ``missed_cycles`` (steps with any
    of braked / late / stale, each counted once, plus the dropped ones),
    ``cpu_ms`` {node: CPU per step}, ``p99_ms`` {sim, estimator, controller}: the largest in-node
    processing p99 any node reported over the steady state (each report is the p99 of its last
    1000 samples, so this is the worst 1 s window), ``load`` (before, after). ``node_params``
    {"sim"|"estimator"|"controller": {parameter: value}} adds parameters to one node (e.g. its
    ``cpu_affinity`` and ``niceness``). ``controller_argv``: start that program as the controller
    instead of ``pd_feedforward`` (e.g. bench_rcl_floor's C controller; it reports no p99)."""
    own = node_params or {}
    launch.node("estimator", "payload_estimator", "cdpr", {"poll_period": 0.01} | params | own.get("estimator", {}))
    if controller_argv:
        launch.start("controller", controller_argv)
    else:
        launch.node("controller", "pd_feedforward", "cdpr", params | own.get("controller", {}))
    cl = _Client(launch.domain_id)       # listens to /diagnostics only (1 Hz): no extra 1 kHz load
    deadline = time.monotonic() + 60
    ready = {"payload_estimator"} | (set() if controller_argv else {"pd_feedforward"})
    while time.monotonic() < deadline and not ready <= set(cl.diag):
        cl.spin(0.2)
    launch.node("sim", "cable_sim_node", "cdpr", {"rate": 1000.0, "real_time": True, "payload_mass": 249.0,
                                                  "duration": seconds + 1.0, "settle": 1.0,
                                                  "extras_every": 10} | params | own.get("sim", {}))
    names = {"sim": "cable_sim_node", "estimator": "payload_estimator", "controller": "pd_feedforward"}
    pids = {name: launch.procs[name].popen.pid for name in names}
    if on_started is not None:
        on_started(pids)                 # e.g. attach a sampling profiler
    load0 = _load()
    t0 = time.monotonic()
    samples = []        # (wall, sim time, commands received by the sim, {name: cpu s}, sim status)
    threads = []        # [(sim time, {node: _threads})] at the first and the latest steady sample
    worst = dict.fromkeys(names, 0.0)
    last_stamp = None
    progress = None
    try:
        from tqdm import tqdm
        progress = tqdm(total=round(seconds + 1.0), unit="sim s", desc="closed loop 1 kHz", file=sys.stderr,
                        bar_format="{desc}: {n:.0f}/{total:.0f} sim s [{elapsed}<{remaining}, {rate_fmt}]")
    except ImportError:
        pass
    while launch.procs["sim"].alive() and time.monotonic() - t0 < 20 * seconds + 60:
        cl.spin(0.05)
        d = cl.diag.get("cable_sim_node")
        if d is None or d.get("sim time s") == last_stamp:
            continue
        last_stamp = d.get("sim time s")
        try:
            cpu = {name: _cpu_seconds(pid) for name, pid in pids.items()}
        except OSError:
            break
        st = float(d["sim time s"])
        if progress is not None:
            progress.update(min(st, progress.total) - progress.n)
        if st >= 1.0:
            try:
                threads[1 if threads else 0:] = [(st, {name: _threads(pid) for name, pid in pids.items()})]
            except OSError:
                pass
            for name, node in names.items():
                v = cl.diag.get(node, {}).get("latency p99 ms")
                if v not in (None, "?"):
                    worst[name] = max(worst[name], float(v))
        samples.append((time.monotonic(), st, int(d.get("effort_commands received", 0)), cpu, dict(d),
                        dict(cl.diag.get("pd_feedforward", {}))))
    if progress is not None:
        progress.close()
    cl.close()
    launch.stop_all()
    steady = [s for s in samples if s[1] >= 1.0]
    if len(steady) < 2:
        log("  closed loop: not enough /diagnostics samples from the simulator")
        return None
    (w0, s0, c0, cpu0, first, _), (w1, s1, c1, cpu1, last, _) = steady[0], steady[-1]
    steps = round((s1 - s0) * 1000)

    def delta(key):
        return int(last.get(key, "0")) - int(first.get(key, "0"))

    out = {"realtime_factor": (s1 - s0) / (w1 - w0), "seconds": s1 - s0, "steps": steps,
           "commands_per_state": (c1 - c0) / max(steps, 1),
           "braked": delta("brake steps after the first command"), "late": delta("late steps"),
           "dropped": delta("dropped steps"), "stale": delta("stale command steps"),
           "cpu_ms": {k: 1000 * (cpu1[k] - cpu0[k]) / max(steps, 1) for k in pids},
           "p99_ms": worst, "load": (load0, _load()),
           "brakes_total": int(last.get("brake steps after the first command", "-1"))}
    out["threads"] = (_thread_deltas(threads[0][1], threads[1][1], round((threads[1][0] - threads[0][0]) * 1000))
                      if len(threads) > 1 else {})
    out["missed_cycles"] = delta("missed steps") + out["dropped"]   # each step counted once
    key = "publishes over 0.2 ms (joint states/tensions/reference)"
    if key in first and key in last:   # the simulator's compiled path
        out.update(sim_slow_publishes=[int(b) - int(a) for a, b in zip(first[key].split("/"), last[key].split("/"))],
                   sim_publish_max_ms=float(last["slowest publish ms"]),
                   sim_wake_max_ms=float(last["latest wake-up ms"]))
    # the controller's compiled path, from its first report that has the count (its report from
    # before the path started may be the newest at the first steady reading)
    slow = "command publishes over 0.2 ms"
    counts = [int(s[5][slow]) for s in steady if slow in s[5]]
    out["slow_publishes"] = counts[-1] - counts[0] if len(counts) > 1 else None

    def ages(d):
        return [int(x) for x in d.get("command age 1/2/3+ periods", "0/0/0").split("/")]

    out["command_age"] = [b - a for a, b in zip(ages(first), ages(last))]   # periods 1, 2, >= 3
    return out


def closed_loop_1khz(bench: Bench, launch, seconds: float, params: dict) -> None:
    bench.section(f"closed loop sim -> estimator -> controller -> sim at 1 kHz, real time, {seconds:g} s")
    r = run_closed_loop(launch, seconds, params, bench.log)
    if r is None:
        return
    bench.row(case="achieved real-time factor (sim time / wall time, steady state)", value=r["realtime_factor"],
              unit="x", target="1 (real time)")
    bench.row(case="commands received by the sim / states published", value=r["commands_per_state"],
              unit="", target="1")
    bench.row(case="missed cycles (steps braked, late or with a stale command, + dropped)",
              value=f"{r['missed_cycles']} (braked {r['braked']}, late {r['late']}, dropped {r['dropped']}, "
                    f"stale {r['stale']})",
              unit=f"of {r['steps']}", target="0")
    age = r["command_age"]
    bench.row(case="applied command answers the state 1 / 2 / >= 3 periods back",
              value=" / ".join(str(a) for a in age), unit="steps", target="all 1")
    bench.row(case="CPU per step: sim / estimator / controller (all threads)",
              value=" / ".join(f"{v:.3f}" for v in r["cpu_ms"].values()), unit="ms", target="")
    bench.log(f"  load average before/after: {r['load'][0]} / {r['load'][1]}")
    bench.row(case="sim / estimator / controller processing p99 (in node, worst 1 s window)",
              value=" / ".join(f"{v:.3f}" for v in r["p99_ms"].values()), unit="ms", target="< 1 ms")


def paper_tables(bench: Bench) -> None:
    """001 Tables I-II and Fig. 15 from offline closed-loop runs (MP, MP+M1, MP+M2)."""
    from cablelab.plants.cdpr.estimate import estimate_arrays
    from cablelab.plants.cdpr.dataset import CdprArrays
    from cablelab.plants.cdpr.sim import CdprTruth, default_description, simulate, without_pulley_radius

    desc = default_description()
    desc1 = without_pulley_radius(desc)
    c = desc.cdpr
    scale = c.gear_ratio / c.drum_radius
    t1, t2, f15 = [], [], []
    for name, pl in (("MP", 0.0), ("MP+M1", 122.0), ("MP+M2", 249.0)):
        bench.log(f"  {name}: PDFF and PD runs")
        run = simulate(desc, CdprTruth(payload_mass=pl, seed=7), controller="pdff")
        pd = simulate(desc, CdprTruth(payload_mass=pl, seed=7), controller="pd")
        true = run.true_mass

        def arr(source):
            ten = run.tension if source == "dynamometer" else run.motor_torque * scale
            return CdprArrays(run.t, ten, run.motor_velocity, run.motor_torque, run.ref_position, None,
                              run.ref_acceleration, run.ref_velocity, true, None, source, scale)

        def stats(e):
            err = 100 * (e.mass - true) / true
            return e.mass.mean(), 100 * (e.mass.mean() - true) / true, np.abs(err).max(), e.mass.std()

        m1 = stats(estimate_arrays(arr("dynamometer"), desc1))
        m2 = stats(estimate_arrays(arr("dynamometer"), desc))
        raw = stats(estimate_arrays(arr("motor"), desc))
        fr = stats(estimate_arrays(arr("motor"), desc, ("winch_coulomb_friction", "winch_viscous_friction")))
        t1.append((name, true, m1, m2))
        t2.append((name, raw, fr, m2))
        ez = lambda r: 1000 * np.abs(r.true_position[:, 2] - r.ref_position[:, 2]).max()  # noqa: E731
        f15.append((name, ez(pd), ez(run)))
    bench.section("001 Table I: estimated mass with Models I and II (dynamometers, desired pose)")
    for name, true, m1, m2 in t1:
        bench.row(payload=name, real_kg=true, modelI_kg=m1[0], modelII_kg=m2[0], modelI_err_pct=m1[1],
                  modelII_err_pct=m2[1], modelI_std=m1[3], modelII_std=m2[3])
    bench.section("001 Table II: dynamometers vs motor torques (Model II)")
    for name, raw, fr, dyn in t2:
        bench.row(payload=name, raw_mean=raw[0], raw_err_pct=raw[1], raw_max_pct=raw[2], raw_std=raw[3],
                  fric_mean=fr[0], fric_max_pct=fr[2], fric_std=fr[3], dyn_mean=dyn[0], dyn_max_pct=dyn[2],
                  dyn_std=dyn[3])
    bench.section("001 Fig. 15: max |z error| (mm), PD vs PDFF")
    for name, a, b in f15:
        bench.row(payload=name, PD_mm=a, PDFF_mm=b)


def main(argv=None) -> int:
    bench = Bench("cdpr", __doc__)
    bench.parser.add_argument("--samples", type=int, default=1_000_000)
    bench.parser.add_argument("--seconds", type=float, default=10.0, help="node tests length (10)")
    bench.parser.add_argument("--skip-nodes", action="store_true")
    bench.parser.add_argument("--only-loop", action="store_true", help="only the 1 kHz closed loop")
    bench.parser.add_argument("--paper", action="store_true", help="001 Tables I-II, Fig. 15 instead")
    bench.parser.add_argument("--executor", choices=("fast", "rclpy"), default="fast",
                              help="spin the nodes with FastExecutor (default) or rclpy's "
                                   "SingleThreadedExecutor (fast_executor:=false), for comparison")
    bench.parser.add_argument("--nodes-only", action="store_true", help="skip the offline parts")
    bench.parser.add_argument("--rt-priority", type=int, default=0,
                              help="run the nodes under SCHED_FIFO at this priority (rt_priority)")
    args = bench.parse(argv)
    if args.paper:
        paper_tables(bench)
        bench.done()
        return 0
    if not args.only_loop and not args.nodes_only:
        offline_estimation(bench, args.samples)
        offline_simulation(bench)
        estimator_in_process(bench)
    if not args.skip_nodes:
        from cablelab.ros.launch import Launcher

        tmp = Path(tempfile.mkdtemp(prefix="bench-cdpr-"))
        with Launcher(log_dir=tmp / "logs") as launch:
            bench.log(f"ROS_DOMAIN_ID {launch.domain_id}, logs in {launch.log_dir}")
            params = {} if args.executor == "fast" else {"fast_executor": False}
            if args.rt_priority:
                params["rt_priority"] = args.rt_priority
            if not args.only_loop:
                estimator_node(bench, launch, args.seconds, params)
            closed_loop_1khz(bench, launch, args.seconds, params)
    bench.done()
    return 0


if __name__ == "__main__":
    sys.exit(main())
