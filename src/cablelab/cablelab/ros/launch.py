"""Start nodes as subprocesses on one ROS_DOMAIN_ID, wait until topics flow, stop them cleanly.

Used by the integration tests, the benchmarks and the demo::

    with Launcher(domain_id=42, log_dir=tmp) as launch:
        launch.start("sim", [sys.executable, "-m", "cable_sim_node.main", "--plant", "axis"])
        launch.wait_for_topics({"/axis/joint_states": 10}, timeout=60)
        ...
    # on exit: SIGINT to every process, then SIGTERM, then SIGKILL after the grace times

Every child gets ``ROS_DOMAIN_ID`` and ``ROS_AUTOMATIC_DISCOVERY_RANGE=LOCALHOST`` in its
environment, unbuffered output, and its stdout+stderr in ``log_dir/<name>.log``; it receives
SIGTERM if the launching process dies without stopping it (no orphan nodes). Domain ids come from
:func:`reserve_domain_id` (locked per machine, so parallel runs never share one).
"""
from __future__ import annotations

import os
import signal
import subprocess
import sys
import tempfile
import time
from dataclasses import dataclass, field
from pathlib import Path

from ..errors import CablelabError


_DOMAIN_LOCKS = Path(tempfile.gettempdir()) / "cablelab-ros-domains"
_held_domains: dict[int, int] = {}  # domain id -> fd of its flock'd lock file


def reserve_domain_id(salt: int = 0, lo: int = 1, hi: int = 200) -> int:
    """A ROS_DOMAIN_ID in ``lo..hi`` that no other process on this machine holds.

    The search starts at a place derived from the pid and ``salt`` and takes the first id whose
    lock file (``$TMPDIR/cablelab-ros-domains/<id>.lock``) this process can ``flock``: several
    test runs, demos and benchmarks at once never share a domain (nodes of one run would see
    the other's topics). The lock is held until :func:`release_domain_id` or the end of the
    process (the kernel drops it even after SIGKILL). Raises CablelabError if all are taken."""
    import fcntl

    _DOMAIN_LOCKS.mkdir(mode=0o777, exist_ok=True)
    n = hi - lo + 1
    start = (os.getpid() * 7 + salt * 37) % n
    for k in range(n):
        d = lo + (start + k) % n
        if d in _held_domains:
            continue
        fd = os.open(_DOMAIN_LOCKS / f"{d}.lock", os.O_RDWR | os.O_CREAT, 0o666)
        try:
            fcntl.flock(fd, fcntl.LOCK_EX | fcntl.LOCK_NB)
        except OSError:
            os.close(fd)
            continue
        _held_domains[d] = fd
        return d
    raise CablelabError(f"no free ROS_DOMAIN_ID in {lo}..{hi} (all locked in {_DOMAIN_LOCKS})")


def release_domain_id(domain_id: int) -> None:
    """Give back a domain id from :func:`reserve_domain_id` (no-op for others)."""
    fd = _held_domains.pop(int(domain_id), None)
    if fd is not None:
        os.close(fd)


def unique_domain_id(salt: int = 0) -> int:
    """A ROS_DOMAIN_ID in 1..200 free on this machine, held for the rest of the process
    (:func:`reserve_domain_id`)."""
    return reserve_domain_id(salt)


def _die_with_parent() -> None:
    """In the child before exec: SIGTERM when the launching process dies (even by SIGKILL), so a
    killed test run or demo leaves no orphan nodes behind (Linux prctl PR_SET_PDEATHSIG)."""
    try:
        import ctypes

        ctypes.CDLL(None, use_errno=True).prctl(1, signal.SIGTERM, 0, 0, 0)
    except (OSError, AttributeError):
        pass


def ros_env(domain_id: int, extra: dict | None = None) -> dict:
    """Environment of the launched processes: their own domain, discovery on this host only, and
    Fast DDS data over shared memory only (``FASTDDS_BUILTIN_TRANSPORTS=SHM`` unless already set):
    with the default transports the samples between the launched processes go over UDP
    loopback, and one 8-double publish costs more thread CPU and wall time (docs/benchmarks.md,
    ``bench_publish.py``). The launched processes are on one host by
    construction (discovery range LOCALHOST)."""
    env = dict(os.environ)
    env.setdefault("FASTDDS_BUILTIN_TRANSPORTS", "SHM")
    env.update({"ROS_DOMAIN_ID": str(domain_id), "ROS_AUTOMATIC_DISCOVERY_RANGE": "LOCALHOST",
                "PYTHONUNBUFFERED": "1", "RCUTILS_COLORIZED_OUTPUT": "0"})
    env.pop("ROS_LOCALHOST_ONLY", None)
    env.update(extra or {})
    return env


@dataclass
class Process:
    name: str
    argv: list[str]
    popen: subprocess.Popen
    log_path: Path
    log_file: object = field(repr=False, default=None)

    def alive(self) -> bool:
        return self.popen.poll() is None

    def log(self) -> str:
        try:
            return self.log_path.read_text(errors="replace")
        except OSError:
            return ""

    def signal(self, sig: int) -> None:
        if self.alive():
            self.popen.send_signal(sig)

    def wait(self, timeout: float) -> int | None:
        try:
            return self.popen.wait(timeout=timeout)
        except subprocess.TimeoutExpired:
            return None


class Launcher:
    """Starts and stops a set of node processes (see module docstring)."""

    def __init__(self, domain_id: int | None = None, log_dir=None, env: dict | None = None):
        self.domain_id = unique_domain_id() if domain_id is None else int(domain_id)
        self.log_dir = Path(log_dir or tempfile.mkdtemp(prefix="cablelab-launch-"))
        self.log_dir.mkdir(parents=True, exist_ok=True)
        self.env = ros_env(self.domain_id, env)
        self.procs: dict[str, Process] = {}
        self._probe: Probe | None = None

    def __enter__(self) -> "Launcher":
        return self

    def __exit__(self, *exc) -> bool:
        self.stop_all()
        return False

    def start(self, name: str, argv: list[str], env: dict | None = None) -> Process:
        """Start ``argv`` as process ``name`` (output to ``log_dir/name.log``)."""
        log_path = self.log_dir / f"{name}.log"
        fh = open(log_path, "wb")
        popen = subprocess.Popen([str(a) for a in argv], stdout=fh, stderr=subprocess.STDOUT,
                                 env={**self.env, **(env or {})}, process_group=0,
                                 preexec_fn=_die_with_parent if sys.platform.startswith("linux") else None)
        proc = Process(name, list(argv), popen, log_path, fh)
        self.procs[name] = proc
        return proc

    def node(self, name: str, package: str, plant: str, params: dict | None = None,
             extra: list[str] | None = None) -> Process:
        """Start a cablelab node (``python -m <package>.main --plant P --ros-args -p k:=v``)."""
        argv = [sys.executable, "-m", f"{package}.main", "--plant", plant] + list(extra or [])
        if params:
            argv.append("--ros-args")
            for k, v in params.items():
                argv += ["-p", f"{k}:={v}"]
        return self.start(name, argv)

    def stop(self, name: str, grace: float = 15.0) -> int | None:
        """SIGINT, then SIGTERM after ``grace`` s, then SIGKILL. Returns the exit code."""
        proc = self.procs[name]
        code = None
        for sig in (signal.SIGINT, signal.SIGTERM):
            proc.signal(sig)
            code = proc.wait(grace)
            if code is not None:
                break
        if code is None:
            proc.signal(signal.SIGKILL)
            code = proc.wait(10)
        if proc.log_file is not None:
            proc.log_file.close()
            proc.log_file = None
        return code

    def kill(self, name: str) -> int | None:
        """SIGKILL (for tests of what a crash leaves behind)."""
        proc = self.procs[name]
        proc.signal(signal.SIGKILL)
        return proc.wait(10)

    def stop_all(self, grace: float = 15.0) -> dict[str, int | None]:
        """Stop every process, most recently started first, and close the probe."""
        codes = {name: self.stop(name, grace) for name in reversed(list(self.procs))}
        if self._probe is not None:
            self._probe.close()
            self._probe = None
        return codes

    def stop_all_checked(self, label: str, logs, grace: float = 15.0) -> None:
        """:meth:`stop_all`; RuntimeError naming ``label``, the processes that exited with an
        error code and where their ``logs`` are when any did."""
        codes = self.stop_all(grace)
        bad = {k: v for k, v in codes.items() if v != 0}
        if bad:
            raise RuntimeError(f"{label}: processes exited with {bad}; logs in {logs}")

    def check_alive(self) -> None:
        """CablelabError naming a process that failed (exit code != 0), with the end of its log."""
        for proc in self.procs.values():
            if not proc.alive() and proc.popen.returncode != 0:
                tail = " | ".join(proc.log().strip().splitlines()[-5:])
                raise CablelabError(f"process {proc.name} exited with {proc.popen.returncode}: {tail}")

    def probe(self) -> "Probe":
        """This launcher's in-process graph probe (one DDS participant on the domain, kept until
        :meth:`stop_all`: creating and destroying participants next to starting nodes slows
        discovery on a busy machine)."""
        if self._probe is None:
            self._probe = Probe(self.domain_id)
        return self._probe

    def wait_for_topics(self, counts: dict[str, int], timeout: float = 60.0) -> dict[str, int]:
        """Subscribe (in this process, on this domain) and wait until every topic delivered its
        count of messages. Raises CablelabError naming the silent topics on timeout (or a dead
        process). Returns the counts seen."""
        return self.probe().wait_for_topics(counts, timeout, self.check_alive)

    def wait_for_subscribers(self, topics, timeout: float = 60.0, node_name: str | None = None) -> None:
        """Wait until every topic has a subscription in the graph (of the node ``node_name`` if
        given), e.g. until a recorder that is still importing is ready before the publishers
        start. Raises CablelabError naming the topics on timeout (or a dead process)."""
        self.probe().wait_for_subscribers(list(topics), timeout, node_name, self.check_alive)

    def wait_for_recorded(self, bag_dir, counts: dict[str, int], timeout: float = 60.0,
                          poll: float = 0.5) -> dict[str, int]:
        """Wait until the bag a recorder is writing to ``bag_dir`` holds at least ``counts``
        messages per topic (read like ``cablelab info --recover``: everything flushed so far).
        What the recorder got is what a test checks; what a probe saw is only a hint, since every
        subscriber matches each publisher at its own time. Raises CablelabError naming the short
        topics on timeout (or a dead process). Returns the counts seen."""
        from ..bags import open_bag

        deadline = time.monotonic() + timeout
        seen: dict[str, int] = {}
        while time.monotonic() < deadline:
            self.check_alive()
            try:
                got = open_bag(bag_dir, recover=True).counts
            except CablelabError:
                got = {}  # not created or nothing flushed yet
            seen = {t: int(got.get(t, 0)) for t in counts}
            if all(seen[t] >= n for t, n in counts.items()):
                return seen
            time.sleep(poll)
        short = [t for t, n in counts.items() if seen.get(t, 0) < n]
        raise CablelabError(f"timeout after {timeout:g} s waiting for {bag_dir} to record "
                            f"{short} (domain {self.domain_id}, recorded {seen})")


class Probe:
    """An rclpy node in its own context on ``domain_id``, for watching the graph and topics."""

    def __init__(self, domain_id: int):
        import rclpy
        from rclpy.context import Context
        from rclpy.executors import SingleThreadedExecutor
        from rclpy.node import Node

        self.domain_id = domain_id
        self.ctx = Context()
        rclpy.init(context=self.ctx, domain_id=domain_id)
        self.node = Node("cablelab_probe", context=self.ctx)
        self.executor = SingleThreadedExecutor(context=self.ctx)
        self.executor.add_node(self.node)

    def close(self) -> None:
        import rclpy

        try:
            self.node.destroy_node()
        finally:
            rclpy.try_shutdown(context=self.ctx)

    def wait_for_subscribers(self, topics: list[str], timeout: float = 60.0,
                             node_name: str | None = None, check=None) -> None:
        deadline = time.monotonic() + timeout
        missing = list(topics)
        while time.monotonic() < deadline:
            missing = [t for t in topics if not any(
                node_name is None or i.node_name == node_name
                for i in self.node.get_subscriptions_info_by_topic(t))]
            if not missing:
                return
            if check is not None:
                check()
            self.executor.spin_once(timeout_sec=0.1)
        raise CablelabError(f"timeout after {timeout:g} s waiting for subscribers on {missing} "
                            f"(domain {self.domain_id})")

    def wait_for_topics(self, counts: dict[str, int], timeout: float = 60.0,
                        check=None) -> dict[str, int]:
        """Subscribe and wait until every topic delivered its count of messages (types from the
        graph; QoS chosen from the publishers: transient-local if they all are, else best
        effort, which matches reliable and best-effort publishers alike)."""
        from rclpy.qos import DurabilityPolicy, HistoryPolicy, QoSProfile, ReliabilityPolicy

        from .convert import message_class
        from .qos import DESCRIPTION_QOS

        probe_qos = QoSProfile(history=HistoryPolicy.KEEP_LAST, depth=100,
                               reliability=ReliabilityPolicy.BEST_EFFORT)
        node = self.node
        seen = {t: 0 for t in counts}
        subs = {}
        try:
            deadline = time.monotonic() + timeout
            while time.monotonic() < deadline:
                if len(subs) < len(counts):
                    types = dict(node.get_topic_names_and_types())
                    for topic in counts:
                        if topic in subs or topic not in types:
                            continue
                        infos = node.get_publishers_info_by_topic(topic)
                        if not infos:
                            continue  # only subscribers so far: choose the QoS once publishers exist
                        cls = message_class(types[topic][0])

                        def cb(_msg, topic=topic):
                            seen[topic] += 1
                        latched = all(i.qos_profile.durability == DurabilityPolicy.TRANSIENT_LOCAL
                                      for i in infos)
                        qos = DESCRIPTION_QOS if latched else probe_qos
                        subs[topic] = node.create_subscription(cls, topic, cb, qos, raw=True)
                self.executor.spin_once(timeout_sec=0.05)
                if all(seen[t] >= n for t, n in counts.items()):
                    return seen
                if check is not None:
                    check()
            silent = [t for t, n in counts.items() if seen[t] < n]
            raise CablelabError(f"timeout after {timeout:g} s waiting for topics {silent} "
                                f"(domain {self.domain_id}, seen {seen})")
        finally:
            for sub in subs.values():
                node.destroy_subscription(sub)


def wait_for_topics(counts: dict[str, int], domain_id: int, timeout: float = 60.0,
                    check=None) -> dict[str, int]:
    """One-off :meth:`Probe.wait_for_topics` (own participant, closed afterwards)."""
    probe = Probe(domain_id)
    try:
        return probe.wait_for_topics(counts, timeout, check)
    finally:
        probe.close()
