"""`cablelab record` / `cablelab replay` as real processes: clean stops leave complete bags, a
SIGKILL leaves the flushed part readable with --recover, bad input is one line, replay
republishes the same bytes with /clock and a transient-local /plant_description."""
from __future__ import annotations

import signal
import subprocess
import sys
import time

import numpy as np
import pytest

from cablelab.bags import BagWriter, open_bag
from cablelab.errors import CablelabError


def _record(launcher, name, bag_dir, *extra, wait=True):
    """Start a recorder of the axis topics and (by default) wait until it subscribed."""
    proc = launcher.start(name, [sys.executable, "-m", "cablelab.cli", "record", "--plant", "axis",
                                 "-o", bag_dir, "--quiet", *extra])
    if wait:
        launcher.wait_for_subscribers(["/axis/joint_states", "/clock"], timeout=120,
                                      node_name="cablelab_recorder")
    return proc


@pytest.mark.parametrize("sig", [signal.SIGINT, signal.SIGTERM])
def test_recorder_stopped_by_signal_leaves_complete_bag(launcher, tmp_path, sig):
    bag_dir = tmp_path / "bag"
    rec = _record(launcher, "recorder", bag_dir)
    launcher.node("sim", "cable_sim_node", "axis", {"rate": 200.0})
    # (on a busy machine DDS matching takes a while after the subscriptions appear: wait until
    # the bag really holds data)
    launcher.wait_for_recorded(bag_dir, {"/axis/joint_states": 60, "/plant_description": 1}, timeout=120)
    # a recorder descheduled for 1.5 s (a loaded machine, made certain): it catches up, since the
    # publishers keep 10 s of history for reliable readers
    rec.signal(signal.SIGSTOP)
    time.sleep(1.5)
    rec.signal(signal.SIGCONT)
    launcher.wait_for_recorded(bag_dir, {"/axis/joint_states": 400}, timeout=120)
    rec.signal(sig)
    assert rec.wait(60) == 0, rec.log()
    bag = open_bag(bag_dir)  # complete: footer and metadata.yaml
    assert (bag_dir / "metadata.yaml").exists() and not bag.recovered
    js = bag.joint_state("/axis/joint_states")
    assert len(js.t) > 400
    np.testing.assert_allclose(np.diff(js.t), 1 / 200.0, atol=1e-9)  # no gap: nothing dropped
    assert bag.description.plant == "axis"


def test_recorder_sigkill_leaves_flushed_part_readable(launcher, tmp_path):
    bag_dir = tmp_path / "bag"
    _record(launcher, "recorder", bag_dir, "--flush-period", "0.2")
    launcher.node("sim", "cable_sim_node", "axis", {"rate": 200.0})
    launcher.wait_for_recorded(bag_dir, {"/axis/joint_states": 100}, timeout=120)
    launcher.kill("recorder")
    assert not (bag_dir / "metadata.yaml").exists()
    with pytest.raises(CablelabError) as exc:
        open_bag(bag_dir)
    assert "truncated" in str(exc.value) and "--recover" in str(exc.value)
    bag = open_bag(bag_dir, recover=True)
    assert bag.recovered
    js = bag.joint_state("/axis/joint_states")
    assert len(js.t) > 50  # everything up to the last flush (every 0.2 s)
    np.testing.assert_allclose(np.diff(js.t), 1 / 200.0, atol=1e-9)
    # the CLI says the same in one line, and reads it with --recover
    out = subprocess.run([sys.executable, "-m", "cablelab.cli", "info", str(bag_dir)],
                         capture_output=True, text=True)
    assert out.returncode == 2 and out.stderr.count("\n") == 1 and "truncated" in out.stderr
    out = subprocess.run([sys.executable, "-m", "cablelab.cli", "info", str(bag_dir), "--recover"],
                         capture_output=True, text=True)
    assert out.returncode == 0 and "/axis/joint_states" in out.stdout


def test_record_refuses_existing_bag_without_overwrite(tmp_path):
    bag_dir = tmp_path / "bag"
    with BagWriter(bag_dir) as w:
        w.write_clock([0.0, 1.0])
    before = (bag_dir / "bag.mcap").read_bytes()
    out = subprocess.run([sys.executable, "-m", "cablelab.cli", "record", "--plant", "axis", "-o",
                          str(bag_dir)], capture_output=True, text=True, timeout=60)
    assert out.returncode == 2
    assert out.stderr.count("\n") == 1 and str(bag_dir) in out.stderr and "--overwrite" in out.stderr
    assert (bag_dir / "bag.mcap").read_bytes() == before
    out = subprocess.run([sys.executable, "-m", "cablelab.cli", "replay", str(tmp_path / "nope")],
                         capture_output=True, text=True, timeout=60)
    assert out.returncode == 2 and out.stderr.count("\n") == 1 and "nope" in out.stderr


def test_replay_republishes_same_messages_with_description(launcher, tmp_path):
    src = tmp_path / "src"
    n = 300
    t = 10.0 + np.arange(n) * 0.01  # 3 s at 100 Hz
    rng = np.random.default_rng(3)
    pos = rng.normal(size=(n, 1))
    with BagWriter(src) as w:
        w.write_description("plant: axis\naxis:\n  joint_type: prismatic\n  inertia: 7.0\n")
        w.write_joint_states("/axis/joint_states", t, ["joint"], pos, pos * 2, pos * 3)
        w.write_joint_trajectory("/axis/reference", t, ["joint"], pos)
    rec_dir = tmp_path / "rec"
    # the replayer publishes /plant_description at once, then waits for subscribers on every topic
    rep = launcher.start("replay", [sys.executable, "-m", "cablelab.cli", "replay", src, "--rate", "2",
                                    "--start-delay", "90", "--quiet"])
    launcher.wait_for_topics({"/plant_description": 1}, timeout=60)  # transient-local: late joiner
    _record(launcher, "recorder", rec_dir, wait=False)  # its subscriptions start the replay
    assert rep.wait(150) == 0, rep.log()
    assert launcher.stop("recorder") == 0
    got = open_bag(rec_dir)
    a, b = open_bag(src).joint_state("/axis/joint_states"), got.joint_state("/axis/joint_states")
    assert len(b.t) == n  # the replay waited for the recorder's subscriptions: nothing lost
    np.testing.assert_array_equal(b.position, a.position)
    np.testing.assert_array_equal(b.effort, a.effort)
    np.testing.assert_array_equal(b.t, a.t)
    # paced, not dumped at once (the exact rate is checked in-process in test_replay_pacing; receive
    # times of a recorder on a busy machine are too bursty for a tight bound here)
    assert b.t_receive[-1] - b.t_receive[0] > 0.5, b.t_receive[-1] - b.t_receive[0]
    # /clock synthesised from the bag's log time (the bag had none)
    clock, _ = got.clock()
    assert clock.min() >= t[0] - 1e-9 and clock.max() <= t[-1] + 1e-9 and len(clock) > 100
    assert got.description.axis.inertia == 7.0


BEST_EFFORT_PUBLISHER = """
import time, rclpy
from rclpy.qos import QoSProfile, ReliabilityPolicy
from rosgraph_msgs.msg import Clock
from std_msgs.msg import String
rclpy.init()
node = rclpy.create_node("foreign_sim")
clock = node.create_publisher(Clock, "/clock", QoSProfile(depth=1, reliability=ReliabilityPolicy.BEST_EFFORT))
desc = node.create_publisher(String, "/plant_description", 10)  # volatile, unlike the contract
k = 0
while rclpy.ok():
    msg = Clock()
    msg.clock.sec, msg.clock.nanosec = divmod(k * 10_000_000, 1_000_000_000)
    clock.publish(msg)
    if k % 10 == 0:
        desc.publish(String(data="plant: axis\\naxis:\\n  joint_type: prismatic\\n"))
    k += 1
    time.sleep(0.01)
"""


def test_recorder_adapts_to_best_effort_and_volatile_publishers(launcher, tmp_path):
    """Like rosbag2, the recorder matches what publishers offer (e.g. `ros2 bag play --clock`
    publishes /clock best-effort): otherwise DDS would never deliver those messages."""
    bag_dir = tmp_path / "bag"
    rec = _record(launcher, "recorder", bag_dir)
    launcher.start("foreign", [sys.executable, "-c", BEST_EFFORT_PUBLISHER])
    launcher.wait_for_recorded(bag_dir, {"/clock": 60, "/plant_description": 1}, timeout=120)
    rec.signal(signal.SIGINT)
    assert rec.wait(60) == 0, rec.log()
    bag = open_bag(bag_dir)
    assert bag.counts.get("/clock", 0) > 50, bag.counts
    assert bag.counts.get("/plant_description", 0) >= 1, bag.counts
    assert "best-effort" in rec.log()


def test_replay_pacing_never_early_and_at_rate(tmp_path, domain_id):
    """In process: the replayer publishes each message no earlier than (log time - first) / rate
    after its start (load can only delay it), and the whole bag takes at least its length / rate."""
    import time as _time

    import rclpy
    from rclpy.executors import SingleThreadedExecutor

    from cablelab.ros.replayer import ReplayNode

    t = 5.0 + np.arange(100) * 0.01  # 0.99 s of bag time
    with BagWriter(tmp_path / "b") as w:
        w.write_joint_states("/axis/joint_states", t, ["joint"], np.zeros((100, 1)))
    rclpy.init(domain_id=domain_id)
    try:
        node = ReplayNode(tmp_path / "b", rate=2.0, start_delay=0.0, quiet=True)
        ex = SingleThreadedExecutor()
        ex.add_node(node)
        deadline = _time.monotonic() + 60
        while not node.done and _time.monotonic() < deadline:
            ex.spin_once(timeout_sec=0.05)
        assert node.done
        sent = np.array(node.sent_wall) - node.t0_wall
        due = (t - t[0]) / 2.0
        assert np.all(sent >= due - 1e-6), (sent - due).min()
        assert sent[-1] >= 0.99 / 2.0
        assert np.median(sent - due) < 0.05  # typically on time
        node.destroy_node()
    finally:
        rclpy.try_shutdown()
