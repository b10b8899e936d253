"""DDS benchmarks between separate processes (rmw_fastrtps, localhost, own ROS_DOMAIN_ID).

1. Round-trip latency: this process publishes a ping (std_msgs/Float64MultiArray), an echo
   process republishes it, this process receives it; --pings sequential round trips, median and
   p99 in microseconds.
2. Recorder throughput: a publisher process sends 3 topics at 1 kHz (/cdpr/joint_states and
   /cdpr/cable_tensions JointState with 8 joints, /cdpr/effort_commands Float64MultiArray) for
   --seconds s (target: 60 s, zero drops) while ``cablelab record`` records them; the
   published counts are compared with the bag's, and the header stamps checked for gaps.
"""
from __future__ import annotations

import json
import sys
import tempfile
import time
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parent))
from harness import Bench  # noqa: E402

TOPICS = ("/cdpr/joint_states", "/cdpr/cable_tensions", "/cdpr/effort_commands")


def echo_main() -> int:
    """Echo process: /bench/ping -> /bench/pong."""
    import rclpy
    from rclpy.node import Node
    from std_msgs.msg import Float64MultiArray

    from cablelab.ros.qos import stream_qos

    rclpy.init()
    node = Node("bench_echo")
    pub = node.create_publisher(Float64MultiArray, "/bench/pong", stream_qos(10))
    node.create_subscription(Float64MultiArray, "/bench/ping", lambda m: pub.publish(m), stream_qos(10))
    try:
        rclpy.spin(node)
    except (KeyboardInterrupt, Exception):  # noqa: BLE001 - stopped by the bench
        pass
    rclpy.try_shutdown()
    return 0


def publisher_main(seconds: float) -> int:
    """Publisher process: 3 topics at 1 kHz (10 messages per topic every 10 ms, paced on the
    wall clock so the average rate is exact), then prints the counts as JSON."""
    import rclpy
    from rclpy.node import Node
    from sensor_msgs.msg import JointState
    from std_msgs.msg import Float64MultiArray

    from cablelab.ros import convert
    from cablelab.ros.qos import stream_qos

    rclpy.init()
    node = Node("bench_publisher")
    qos = stream_qos(1000)
    pubs = {TOPICS[0]: node.create_publisher(JointState, TOPICS[0], qos),
            TOPICS[1]: node.create_publisher(JointState, TOPICS[1], qos),
            TOPICS[2]: node.create_publisher(Float64MultiArray, TOPICS[2], qos)}
    deadline = time.monotonic() + 60
    while time.monotonic() < deadline and not all(p.get_subscription_count() for p in pubs.values()):
        rclpy.spin_once(node, timeout_sec=0.05)
    time.sleep(1.0)  # let discovery settle on both sides
    winches = [f"winch_{i + 1}" for i in range(8)]
    cables = [f"cable_{i + 1}" for i in range(8)]
    counts = dict.fromkeys(TOPICS, 0)
    n_total = int(seconds * 1000)
    t0 = time.monotonic()
    k = 0
    vals = np.zeros(8)
    while k < n_total:
        due = min(n_total, int((time.monotonic() - t0) * 1000) + 1)
        while k < due:
            t = k * 1e-3
            vals[:] = np.sin(t + np.arange(8))
            pubs[TOPICS[0]].publish(convert.joint_state_msg(t, winches, vals, vals, vals))
            pubs[TOPICS[1]].publish(convert.joint_state_msg(t, cables, None, None, vals * 1000))
            pubs[TOPICS[2]].publish(convert.float_array_msg(vals))
            for topic in TOPICS:
                counts[topic] += 1
            k += 1
            if k % 10000 == 0:
                el = time.monotonic() - t0
                print(f"publisher: {k}/{n_total} per topic, {el:.0f} s, ETA {max(0, seconds - el):.0f} s",
                      file=sys.stderr, flush=True)
        time.sleep(0.002)
    elapsed = time.monotonic() - t0
    from rclpy.duration import Duration

    for p in pubs.values():
        p.wait_for_all_acked(Duration(seconds=10))
    print(json.dumps({"counts": counts, "elapsed": elapsed}), flush=True)
    rclpy.try_shutdown()
    return 0


def latency(bench: Bench, launch, pings: int) -> None:
    bench.section("DDS round-trip latency")
    import rclpy
    from rclpy.context import Context
    from rclpy.executors import SingleThreadedExecutor
    from rclpy.node import Node
    from std_msgs.msg import Float64MultiArray

    from cablelab.ros.qos import stream_qos

    launch.start("echo", [sys.executable, __file__, "--echo"])
    ctx = Context()
    rclpy.init(context=ctx, domain_id=launch.domain_id)
    node = Node("bench_ping", context=ctx)
    ex = SingleThreadedExecutor(context=ctx)
    ex.add_node(node)
    got = []
    pub = node.create_publisher(Float64MultiArray, "/bench/ping", stream_qos(10))
    node.create_subscription(Float64MultiArray, "/bench/pong", lambda m: got.append(time.perf_counter()),
                             stream_qos(10))
    # wait for the echo to be connected both ways
    deadline = time.monotonic() + 60
    while time.monotonic() < deadline and not got:
        pub.publish(Float64MultiArray(data=[0.0]))
        ex.spin_once(timeout_sec=0.1)
    if not got:
        raise RuntimeError("echo process never answered")
    time.sleep(0.5)
    for _ in range(20):
        ex.spin_once(timeout_sec=0.01)
    rtts = []
    msg = Float64MultiArray(data=[0.0] * 8)
    for i in range(pings):
        got.clear()
        t0 = time.perf_counter()
        pub.publish(msg)
        limit = t0 + 1.0
        while not got and time.perf_counter() < limit:
            ex.spin_once(timeout_sec=0.5)
        if got:
            rtts.append(got[0] - t0)
    node.destroy_node()
    rclpy.try_shutdown(context=ctx)
    launch.stop("echo")
    rtt = np.array(rtts) * 1e6
    bench.row(case="round trip ping->echo->pong (2 processes)", n=len(rtt), median_us=float(np.median(rtt)),
              p99_us=float(np.quantile(rtt, 0.99)), max_us=float(rtt.max()), lost=pings - len(rtt))


def recorder(bench: Bench, launch, seconds: float, tmp: Path) -> None:
    from cablelab.bags import open_bag

    bench.section(f"recorder: 3 topics at 1 kHz for {seconds:g} s")
    bag_dir = tmp / "rec"
    rec = launch.start("recorder", [sys.executable, "-m", "cablelab.cli", "record", "--topics",
                                    ",".join(TOPICS), "-o", bag_dir, "--quiet"])
    pub = launch.start("publisher", [sys.executable, __file__, "--publisher", "--seconds", str(seconds)])
    code = pub.wait(seconds * 3 + 120)
    if code != 0:
        raise RuntimeError(f"publisher failed: {pub.log()[-2000:]}")
    report = json.loads([ln for ln in pub.log().splitlines() if ln.startswith("{")][-1])
    time.sleep(1.0)
    launch.stop("recorder")
    if rec.popen.returncode != 0:
        raise RuntimeError(f"recorder failed: {rec.log()[-2000:]}")
    bag = open_bag(bag_dir)
    for topic in TOPICS:
        sent = report["counts"][topic]
        recorded = bag.counts.get(topic, 0)
        gaps = 0
        if topic != TOPICS[2] and recorded:
            t = bag.joint_state(topic).t
            gaps = int(np.sum(np.round(np.diff(t) * 1000) != 1))
        bench.row(case=f"recorder {topic}", published=sent, recorded=recorded, dropped=sent - recorded,
                  stamp_gaps=gaps, rate_hz=sent / report["elapsed"], seconds=report["elapsed"])


def main(argv=None) -> int:
    argv = list(sys.argv[1:] if argv is None else argv)
    if "--echo" in argv:
        return echo_main()
    if "--publisher" in argv:
        return publisher_main(float(argv[argv.index("--seconds") + 1]))
    bench = Bench("dds", __doc__)
    bench.parser.add_argument("--seconds", type=float, default=60.0, help="recorder test length (60)")
    bench.parser.add_argument("--pings", type=int, default=2000, help="round trips (2000)")
    bench.parser.add_argument("--skip-recorder", action="store_true")
    args = bench.parse(argv)

    from cablelab.ros.launch import Launcher

    tmp = Path(tempfile.mkdtemp(prefix="bench-dds-"))
    with Launcher(log_dir=tmp / "logs") as launch:
        bench.log(f"ROS_DOMAIN_ID {launch.domain_id}, logs in {launch.log_dir}")
        latency(bench, launch, args.pings)
        if not args.skip_recorder:
            bench.log(f"recorder: 3 topics at 1 kHz for {args.seconds:g} s")
            recorder(bench, launch, args.seconds, tmp)
    bench.done()
    return 0


if __name__ == "__main__":
    sys.exit(main())
