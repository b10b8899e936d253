"""CPU cost of one DDS publish between two processes, per Fast DDS transport setting.

This process publishes a ``std_msgs/Float64MultiArray`` of 8 doubles (the CDPR command) at
~1 kHz to the echo process of ``bench_dds.py`` (its own process, own ROS_DOMAIN_ID), as
pre-serialised bytes (``RawTemplate``, what the CDPR nodes publish) and as an rclpy message, and
measures the publishing thread's CPU time (``time.thread_time``) and the wall time of each
``publish`` call. One child launch per transport setting (``FASTDDS_BUILTIN_TRANSPORTS`` for both
processes: ``DEFAULT`` = Fast DDS's own choice, ``SHM``, ``UDPv4``).

    ./run python bench/bench_publish.py [--messages 3000] [--transports DEFAULT,SHM,UDPv4] [--json]
"""
from __future__ import annotations

import json
import os
import subprocess
import sys
import time
from pathlib import Path

import numpy as np

HERE = Path(__file__).resolve().parent
sys.path.insert(0, str(HERE))
from harness import Bench  # noqa: E402


def child(messages: int) -> int:
    """Publisher side (FASTDDS_BUILTIN_TRANSPORTS already in the environment): prints JSON."""
    import rclpy
    from rclpy.context import Context
    from rclpy.node import Node
    from std_msgs.msg import Float64MultiArray

    from cablelab.ros import convert
    from cablelab.ros.launch import Launcher
    from cablelab.ros.qos import stream_qos
    from cablelab.ros.rawmsg import RawTemplate

    transports = os.environ.get("FASTDDS_BUILTIN_TRANSPORTS", "DEFAULT")
    with Launcher(env={"FASTDDS_BUILTIN_TRANSPORTS": transports}) as launch:
        launch.start("echo", [sys.executable, str(HERE / "bench_dds.py"), "--echo"])
        ctx = Context()
        rclpy.init(context=ctx, domain_id=launch.domain_id)
        node = Node("bench_publish", context=ctx)
        pub = node.create_publisher(Float64MultiArray, "/bench/ping", stream_qos(100))
        t0 = time.monotonic()
        while pub.get_subscription_count() == 0 and time.monotonic() - t0 < 60:
            time.sleep(0.1)
        time.sleep(1.0)
        tpl = RawTemplate(convert.float_array_msg(np.zeros(8)))
        msg = convert.float_array_msg(np.zeros(8))
        out = {}
        for kind in ("bytes", "message"):
            cpu = 0.0
            wall = np.empty(messages)
            for k in range(messages):
                c0, w0 = time.thread_time(), time.perf_counter()
                pub.publish(tpl.data() if kind == "bytes" else msg)
                cpu += time.thread_time() - c0
                wall[k] = time.perf_counter() - w0
                time.sleep(0.001)
            out[kind] = {"cpu_us": 1e6 * cpu / messages, "wall_median_us": 1e6 * float(np.median(wall)),
                         "wall_p99_us": 1e6 * float(np.quantile(wall, 0.99))}
        node.destroy_node()
        rclpy.try_shutdown(context=ctx)
    print(json.dumps(out))
    return 0


def main(argv=None) -> int:
    argv = sys.argv[1:] if argv is None else argv
    if "--child" in argv:
        return child(int(argv[argv.index("--child") + 1]))
    bench = Bench("publish", __doc__)
    bench.parser.add_argument("--messages", type=int, default=3000)
    bench.parser.add_argument("--transports", default="DEFAULT,SHM,UDPv4")
    args = bench.parse(argv)
    for t in args.transports.split(","):
        env = dict(os.environ, FASTDDS_BUILTIN_TRANSPORTS=t)
        r = subprocess.run([sys.executable, __file__, "--child", str(args.messages)], env=env,
                           capture_output=True, text=True, timeout=600)
        lines = [ln for ln in r.stdout.splitlines() if ln.startswith("{")]
        if r.returncode or not lines:
            bench.log(f"{t}: failed ({r.returncode}): {r.stderr.strip().splitlines()[-1:]}")
            continue
        for kind, v in json.loads(lines[-1]).items():
            bench.row(transports=t, payload=kind, cpu_us=v["cpu_us"], wall_median_us=v["wall_median_us"],
                      wall_p99_us=v["wall_p99_us"])
    bench.done()
    return 0


if __name__ == "__main__":
    sys.exit(main())
