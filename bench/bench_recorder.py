"""What recording costs: CPU time of the ``cablelab record`` node per message, with its
FastExecutor against rclpy's SingleThreadedExecutor, and how many messages per second of CPU
that leaves (the recorder of a 1 kHz simulator takes ~7 topics at 1 kHz = 7000 messages/s).

A publisher process sends ``--messages`` JointStates (8 joints, like the suspended simulator's)
on one topic as fast as it can, with a history deep enough to lose none; the recorder (a child
process running :class:`cablelab.ros.recorder.RecorderNode`) records them. The recorder's CPU
time (user + system, from /proc) is read when the burst starts and when the bag holds every
message. Both recorders run in the same session, one after the other, so the ratio is what
counts on a shared machine.

    ./run python bench/bench_recorder.py [--messages 20000] [--json]
"""
from __future__ import annotations

import argparse
import json
import os
import sys
import tempfile
import time
from pathlib import Path

PUBLISHER = r"""
import sys, time
import rclpy
from rclpy.duration import Duration
from rclpy.node import Node
from cablelab.ros import convert
from cablelab.ros.qos import publisher_qos

n = int(sys.argv[1])
rclpy.init()
node = Node("bench_publisher")
pub = node.create_publisher(convert.message_class("sensor_msgs/msg/JointState"), "/bench", publisher_qos(n + 10))
names = [f"left_{i}" for i in range(1, 5)] + [f"right_{i}" for i in range(1, 5)]
while pub.get_subscription_count() < 1 or not pub.wait_for_all_acked(Duration(seconds=1)):
    pub.publish(convert.joint_state_msg(0.0, names, [0.0] * 8, [0.0] * 8, [0.0] * 8))
    time.sleep(0.2)
print("go", flush=True)
time.sleep(1.0)
for k in range(1, n + 1):
    pub.publish(convert.joint_state_msg(k * 1e-3, names, [0.0] * 8, [0.0] * 8, [0.0] * 8))
pub.wait_for_all_acked(Duration(seconds=120))
"""


def _child(bag: str, fast: bool) -> int:
    from types import SimpleNamespace

    from cablelab.ros.recorder import RecorderNode
    from cablelab.ros.runner import run_node

    return run_node(lambda _a: RecorderNode(bag, {"/bench": "sensor_msgs/msg/JointState"}, quiet=True, fast=fast),
                    SimpleNamespace(), [], "bench_recorder")


def _cpu(pid: int) -> float:
    fields = Path(f"/proc/{pid}/stat").read_text().rsplit(")", 1)[1].split()
    return (int(fields[11]) + int(fields[12])) / os.sysconf("SC_CLK_TCK")


def measure(n: int, fast: bool, tmp: Path) -> dict:
    import numpy as np

    from cablelab.bags import open_bag
    from cablelab.ros.launch import Launcher, release_domain_id, reserve_domain_id

    bag = tmp / ("fast" if fast else "rclpy")
    domain = reserve_domain_id()
    try:
        with Launcher(domain_id=domain, log_dir=tmp / "logs") as launch:
            rec = launch.start("recorder", [sys.executable, __file__, "--child", str(bag), str(int(fast))])
            launch.wait_for_subscribers(["/bench"], timeout=120, node_name="cablelab_recorder")
            pub = launch.start("publisher", [sys.executable, "-c", PUBLISHER, str(n)])
            deadline = time.monotonic() + 120
            while "go" not in pub.log():
                assert time.monotonic() < deadline and pub.alive(), pub.log()
                time.sleep(0.05)
            c0, t0 = _cpu(rec.popen.pid), time.monotonic()
            launch.wait_for_recorded(bag, {"/bench": n + 1}, timeout=600, poll=0.2)
            while (burst := int(np.sum(open_bag(bag, recover=True).joint_state("/bench").t > 0))) < n:
                assert time.monotonic() < deadline + 600, f"recorded {burst} of {n}"
                time.sleep(0.2)
            c1, t1 = _cpu(rec.popen.pid), time.monotonic()
            assert launch.stop("recorder", grace=60) == 0, rec.log()
    finally:
        release_domain_id(domain)
    from cablelab.bags.reader import recorder_lost

    cpu = c1 - c0
    return {"executor": "FastExecutor" if fast else "rclpy SingleThreadedExecutor", "messages": n,
            "recorded": burst, "lost": (recorder_lost(bag) or {}).get("/bench"),
            "cpu_s": cpu, "wall_s": t1 - t0, "us_per_msg": 1e6 * cpu / n, "msgs_per_cpu_s": n / max(cpu, 1e-9)}


def main(argv=None) -> int:
    p = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    p.add_argument("--messages", type=int, default=20000)
    p.add_argument("--json", action="store_true")
    p.add_argument("--child", nargs=2, help=argparse.SUPPRESS)
    args = p.parse_args(argv)
    if args.child:
        return _child(args.child[0], bool(int(args.child[1])))
    with tempfile.TemporaryDirectory(prefix="bench_recorder-") as tmp:
        rows = [measure(args.messages, fast, Path(tmp)) for fast in (False, True)]
    if args.json:
        print(json.dumps(rows))
        return 0
    print(f"{'executor':<30} {'messages':>8} {'recorded':>8} {'lost':>5} {'CPU s':>7} {'us/msg':>7} {'msgs/CPU s':>10}")
    for r in rows:
        print(f"{r['executor']:<30} {r['messages']:>8} {r['recorded']:>8} {r['lost']!s:>5} {r['cpu_s']:>7.2f} "
              f"{r['us_per_msg']:>7.1f} {r['msgs_per_cpu_s']:>10.0f}")
    print(f"CPU per message, rclpy / FastExecutor: {rows[0]['us_per_msg'] / rows[1]['us_per_msg']:.1f}x")
    return 0


if __name__ == "__main__":
    sys.exit(main())
