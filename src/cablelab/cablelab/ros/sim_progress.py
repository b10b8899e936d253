"""Honest progress of a simulation running in other processes: a tqdm bar in *simulated* seconds
(read from ``/clock`` as the simulator publishes it), its rate (simulated s per wall s) and an ETA
from that rate, and a busy-machine note only when the load comes from outside our own process
tree (``/proc``: CPU time of every process minus ours and our children's).

    with SimProgress(launcher.probe(), duration, "pdff") as bar:
        while sim_alive():
            bar.poll(0.5)
"""
from __future__ import annotations

import os
import sys
import time

__all__ = ["SimProgress", "LoadMeter", "process_tree"]


def _stat_fields(pid: int) -> list[str]:
    with open(f"/proc/{pid}/stat") as f:
        return f.read().rsplit(")", 1)[1].split()


def process_tree(root: int | None = None) -> set[int]:
    """Pids of ``root`` (default: this process) and all its descendants (Linux /proc)."""
    root = os.getpid() if root is None else root
    children: dict[int, list[int]] = {}
    for name in os.listdir("/proc"):
        if name.isdigit():
            try:
                children.setdefault(int(_stat_fields(int(name))[1]), []).append(int(name))
            except (OSError, IndexError, ValueError):
                continue
    out, todo = set(), [root]
    while todo:
        p = todo.pop()
        if p not in out:
            out.add(p)
            todo += children.get(p, [])
    return out


def _cpu_ticks(pids) -> int:
    total = 0
    for pid in pids:
        try:
            f = _stat_fields(pid)
            total += int(f[11]) + int(f[12])          # utime + stime of the process (all threads)
        except (OSError, IndexError, ValueError):
            continue                                   # exited meanwhile
    return total


def _busy_ticks() -> int:
    """Busy CPU ticks of the whole machine since boot (/proc/stat: all but idle and iowait)."""
    with open("/proc/stat") as f:
        v = [int(x) for x in f.readline().split()[1:]]
    return sum(v[:8]) - v[3] - v[4]


class LoadMeter:
    """CPU cores used by processes outside our tree between two :meth:`sample` calls."""

    def __init__(self):
        self.cores = os.cpu_count() or 1
        self._last = None
        self.ours = None        # cores used by our tree over the last interval

    def sample(self) -> float | None:
        """Cores used by others since the previous call (None on the first call or off Linux)."""
        try:
            now = (time.monotonic(), _busy_ticks(), _cpu_ticks(process_tree()))
        except OSError:
            return None
        last, self._last = self._last, now
        if last is None or now[0] - last[0] <= 0:
            return None
        hz = os.sysconf("SC_CLK_TCK")
        # our tree's CPU includes children that exited meanwhile only until they exit: clamp at 0
        dt = now[0] - last[0]
        self.ours = (now[2] - last[2]) / hz / dt
        return max(0.0, (now[1] - last[1]) / hz / dt - self.ours)


class SimProgress:
    """tqdm bar over ``duration`` simulated seconds fed by ``/clock`` on ``probe`` (a
    :class:`cablelab.ros.launch.Probe`). Rate and ETA come from simulated-time progress; a note
    says when other processes (not ours) keep more than half of the machine busy."""

    def __init__(self, probe, duration: float, desc: str, busy_fraction: float = 0.5,
                 load_every: float = 5.0):
        from rosgraph_msgs.msg import Clock
        from rclpy.qos import HistoryPolicy, QoSProfile, ReliabilityPolicy
        from tqdm import tqdm

        self.probe = probe
        self.sim_time = 0.0
        qos = QoSProfile(history=HistoryPolicy.KEEP_LAST, depth=10, reliability=ReliabilityPolicy.BEST_EFFORT)
        self._sub = probe.node.create_subscription(Clock, "/clock", self._on_clock, qos)
        self.bar = tqdm(total=round(float(duration), 1), desc=desc, unit="sim s", file=sys.stderr,
                        dynamic_ncols=True, mininterval=0.5,
                        bar_format="{desc}: {percentage:3.0f}%|{bar}| {n:.1f}/{total:.1f} sim s "
                                   "[{elapsed}<{remaining}, {rate_fmt}{postfix}]")
        self.load = LoadMeter()
        self.load.sample()
        self.busy = busy_fraction * self.load.cores
        self.load_every = load_every
        self._t_load = time.monotonic()

    def _on_clock(self, msg) -> None:
        self.sim_time = max(self.sim_time, msg.clock.sec + 1e-9 * msg.clock.nanosec)

    def poll(self, seconds: float) -> None:
        """Spin the probe for ``seconds`` and move the bar to the latest simulated time."""
        end = time.monotonic() + seconds
        while time.monotonic() < end:
            self.probe.executor.spin_once(timeout_sec=min(0.05, max(0.0, end - time.monotonic())))
        n = min(self.sim_time, self.bar.total)
        if n > self.bar.n:
            self.bar.update(n - self.bar.n)
        if time.monotonic() - self._t_load >= self.load_every:
            self._t_load = time.monotonic()
            others = self.load.sample()
            if others is not None:
                self.bar.set_postfix_str(f"other processes use {others:.1f} of {self.load.cores} cores"
                                         if others > self.busy else "", refresh=False)

    def wait_for(self, launch, until: float, name: str, logs, stall: float = 120.0) -> None:
        """Poll until the simulated time reaches ``until`` s, checking that every process of
        ``launch`` (a :class:`cablelab.ros.launch.Launcher`) is alive; no simulated time for
        ``stall`` s of wall time raises RuntimeError naming ``name`` and the ``logs``."""
        last, t_last = 0.0, time.monotonic()
        while self.sim_time < until:
            self.poll(0.5)
            launch.check_alive()
            if self.sim_time > last:
                last, t_last = self.sim_time, time.monotonic()
            elif time.monotonic() - t_last > stall:
                raise RuntimeError(f"{name}: no simulated time for {stall:.0f} s (at {last:.1f} s); "
                                   f"logs in {logs}")

    def close(self) -> None:
        self.bar.close()
        try:
            self.probe.node.destroy_subscription(self._sub)
        except Exception:  # noqa: BLE001 - the probe may be closed already
            pass

    def __enter__(self) -> "SimProgress":
        return self

    def __exit__(self, *exc) -> bool:
        self.close()
        return False
