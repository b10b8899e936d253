"""The CDPR runs the real-time benchmarks share: the simulator holding the start pose and the
three-process 1 kHz loop of the cablelab nodes over DDS (used by ``bench_realtime.py`` and by
``bench_rcl_floor.py --compare``)."""
from __future__ import annotations

import tempfile
from pathlib import Path

import numpy as np


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


def merge_segments(parts: list) -> dict:
    """One result of the same measurement run as consecutive segments (``bench_realtime
    --segments``): counts (ints) and ``seconds`` summed, p99s and maxima the largest, other
    figures (realtime factors, CPU per step) the mean over the segments, ``load`` the first
    reading before and the last after, flags and names the first segment's; every dict with a
    ``missed_cycles`` also gets ``segment_missed``, the count of each segment."""
    def merge(key: str, values: list):
        vals = [v for v in values if v is not None]
        if not vals:
            return None
        first = vals[0]
        if key == "load":
            return (vals[0][0], vals[-1][-1])
        if isinstance(first, dict):
            out = {k: merge(k if "p99" not in key and "max" not in key else key, [v.get(k) for v in vals])
                   for k in first}
            if "missed_cycles" in first:
                out["segment_missed"] = [v.get("missed_cycles") for v in vals]
            return out
        if isinstance(first, (list, tuple)) and first and all(isinstance(x, int) for x in first):
            return [sum(col) for col in zip(*vals)]
        if isinstance(first, bool) or not isinstance(first, (int, float)) or key == "rate_hz":
            return first
        if "p99" in key or "max" in key:
            return max(vals)
        if key == "seconds" or isinstance(first, int):
            return sum(vals)
        return sum(vals) / len(vals)

    return parts[0] if len(parts) == 1 else merge("", list(parts))


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
