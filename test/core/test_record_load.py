"""`cablelab record` on a busy machine, real processes over DDS: beside CPU hogs (busy-looping
processes started by the test) the recorder gets every sample of a 1 kHz simulator, and what a
writer does drop is counted exactly, reported on /diagnostics, in the bag's metadata and by
`cablelab info`.

Oracles: the simulator's own step count and period (sim time k / rate for step k: every stamp
present once, nothing between), and, for the loss count, the publisher's own count of what it
sent against what reached the bag."""
from __future__ import annotations

import json
import signal
import subprocess
import sys
import time

import numpy as np

from cablelab.bags import open_bag
from cablelab.bags.reader import recorder_lost

HOG = [sys.executable, "-c", "while True: pass"]
RATE, DURATION, STOPPED, STOP_WALL = 1000.0, 5.0, 3000, 8.0


def _hogs(launcher, n: int = 2) -> None:
    """``n`` busy-looping processes beside the test (stopped with the launcher's processes)."""
    for i in range(n):
        launcher.start(f"hog{i}", HOG)


def _info(bag_dir) -> dict:
    out = subprocess.run([sys.executable, "-m", "cablelab.cli", "info", str(bag_dir), "--json"],
                         capture_output=True, text=True, timeout=120)
    assert out.returncode == 0, out.stderr
    return json.loads(out.stdout)


def _stamps(bag, topic: str) -> np.ndarray:
    """Header stamps (s) of a recorded topic."""
    if topic.endswith("_pose"):
        return np.asarray(bag.pose(topic).t)
    if topic.endswith("/imu"):
        return np.array([m.header.stamp.sec + 1e-9 * m.header.stamp.nanosec for m in bag.messages(topic)])
    return np.asarray(bag.joint_state(topic).t)


def _wait_sim_time(launcher, t: float, timeout: float) -> None:
    """Wait until the simulator's /diagnostics says its sim time reached ``t`` s, at most
    ``timeout`` s."""
    from diagnostic_msgs.msg import DiagnosticArray

    from cablelab.ros.qos import stream_qos

    probe = launcher.probe()
    now = [0.0]

    def on_diag(msg):
        for st in msg.status:
            for kv in st.values:
                if st.name == "cable_sim_node" and kv.key == "sim time s":
                    now[0] = max(now[0], float(kv.value))
    sub = probe.node.create_subscription(DiagnosticArray, "/diagnostics", on_diag, stream_qos(100))
    try:
        deadline = time.monotonic() + timeout
        while now[0] < t and time.monotonic() < deadline:
            probe.executor.spin_once(timeout_sec=0.1)
    finally:
        probe.node.destroy_subscription(sub)


def test_recorder_gets_every_sample_of_a_1khz_simulator_beside_cpu_hogs(launcher, tmp_path):
    """Two busy-looping processes beside a 1 kHz simulator (real time: nothing slows it down
    for the recorder) and the recorder; the recorder is moreover stopped (SIGSTOP) while the
    simulator publishes 3000 states (at most 8 s wall: a process silent for longer than the DDS
    participant lease, 20 s, is taken for dead and unmatched), a descheduling made certain: the
    writers' history (10 s of a 1 kHz stream) holds what it has not received, and it catches
    up; the simulator, done
    with its duration, exits only once the recorder acknowledged everything (its history ends
    with it). Every step is in the bag."""
    bag_dir = tmp_path / "run"
    _hogs(launcher, 2)
    rec = launcher.start("recorder", [sys.executable, "-m", "cablelab.cli", "record", "--plant", "suspended",
                                      "-o", bag_dir, "--quiet", "--flush-period", "0.2"])
    streams = ["/suspended/joint_states", "/suspended/platform_pose", "/suspended/imu",
               "/suspended/ground_truth/swing", "/suspended/ground_truth/virtual_joints"]
    launcher.wait_for_subscribers(streams, timeout=180, node_name="cablelab_recorder")
    # time starts once the recorder matched and acknowledged (start gate)
    sim = launcher.node("sim", "cable_sim_node", "suspended",
                        {"rate": RATE, "duration": DURATION, "wait_for_subscribers": 1,
                         "start_swing_x": 0.05})
    launcher.wait_for_recorded(bag_dir, {"/suspended/joint_states": 300}, timeout=180, poll=0.1)
    rec.signal(signal.SIGSTOP)
    try:
        _wait_sim_time(launcher, STOPPED / RATE + open_bag(bag_dir, recover=True).joint_state(
            "/suspended/joint_states").t.max(), timeout=STOP_WALL)
    finally:
        rec.signal(signal.SIGCONT)
    assert sim.wait(600) == 0, sim.log()[-2000:]
    n = int(round(DURATION * RATE))
    launcher.wait_for_recorded(bag_dir, {t: n for t in streams}, timeout=300)
    assert launcher.stop("recorder", grace=60) == 0, rec.log()

    bag = open_bag(bag_dir)
    k_all = np.arange(1, n + 1)
    for topic in streams:
        t = _stamps(bag, topic)
        k = np.unique(np.round(t * RATE).astype(int))
        # every step 1..n once (the start state k = 0 may be resent while the gate waits)
        np.testing.assert_array_equal(k[k > 0], k_all, err_msg=topic)
        assert np.allclose(t * RATE, np.round(t * RATE), atol=1e-6), topic
    lost = recorder_lost(bag_dir)
    # (the 3D view /suspended/markers is a keep-last-1 stream: a stopped recorder misses frames
    # of it by design, so only the data streams must be complete)
    assert lost is not None and set(streams) <= set(lost) and not any(lost[t] for t in streams), lost
    assert _info(bag_dir)["lost"] == lost


PUBLISHER = r"""
import os, signal, sys, time
import rclpy
from rclpy.duration import Duration
from rclpy.node import Node
from sensor_msgs.msg import JointState
from cablelab.ros import convert
from cablelab.ros.qos import publisher_qos

recorder_pid, n, depth = int(sys.argv[1]), int(sys.argv[2]), int(sys.argv[3])
rclpy.init()
node = Node("burst")
pub = node.create_publisher(JointState, "/burst", publisher_qos(depth))
deadline = time.monotonic() + 180
while pub.get_subscription_count() < 1 or not pub.wait_for_all_acked(Duration(seconds=1)):
    pub.publish(convert.joint_state_msg(0.0, ["a"], [0.0]))   # probe until matched and acknowledged
    assert time.monotonic() < deadline, "the recorder never matched"
    time.sleep(0.5)
time.sleep(1.0)        # (the recorder learns this topic has a single publisher on its graph poll)
os.kill(recorder_pid, signal.SIGSTOP)   # a recorder descheduled while a burst goes out
for k in range(1, n + 1):
    pub.publish(convert.joint_state_msg(k * 1e-3, ["a"], [float(k)]))
time.sleep(0.5)
os.kill(recorder_pid, signal.SIGCONT)
pub.wait_for_all_acked(Duration(seconds=60))
print("published", n, flush=True)
node.destroy_node()
rclpy.shutdown()
"""


def test_recorder_counts_lost_samples_on_diagnostics_metadata_and_info(launcher, tmp_path):
    """A writer keeping only 20 samples, a recorder stopped (SIGSTOP) during a burst of 3000:
    the writer must drop samples; the recorder counts exactly the ones missing from the bag."""
    from diagnostic_msgs.msg import DiagnosticArray, DiagnosticStatus

    from cablelab.ros.qos import stream_qos

    bag_dir = tmp_path / "burst"
    rec = launcher.start("recorder", [sys.executable, "-m", "cablelab.cli", "record", "--topics", "/burst",
                                      "-o", bag_dir, "--quiet"])
    # (--topics: the recorder subscribes once the publisher appears; the publisher waits for it)
    probe = launcher.probe()
    warned = []

    def on_diag(msg):
        warned.extend(s for s in msg.status if s.name == "cablelab_recorder" and s.level == DiagnosticStatus.WARN)
    probe.node.create_subscription(DiagnosticArray, "/diagnostics", on_diag, stream_qos(100))
    n = 3000
    pub = launcher.start("publisher", [sys.executable, "-c", PUBLISHER, str(rec.popen.pid), str(n), "20"])
    assert pub.wait(300) == 0, pub.log()[-2000:]
    deadline = time.monotonic() + 120
    while not warned and time.monotonic() < deadline:
        probe.executor.spin_once(timeout_sec=0.1)
    assert launcher.stop("recorder", grace=60) == 0, rec.log()

    bag = open_bag(bag_dir)
    js = bag.joint_state("/burst")
    got = np.round(js.position[:, 0]).astype(int)
    burst = got[got > 0]
    missing = n - len(np.unique(burst))
    assert missing > 0                                   # the shallow writer did drop samples
    np.testing.assert_array_equal(np.diff(burst) > 0, True)   # in order, no duplicates
    lost = recorder_lost(bag_dir)
    assert lost == {"/burst": missing}, (lost, missing)
    # /diagnostics: WARN naming the topic and its count (at the time of that status)
    assert warned, "no WARN from the recorder on /diagnostics"
    last = warned[-1]
    assert "/burst" in last.message
    counts = {kv.key: int(kv.value) for kv in last.values if kv.key.startswith("lost ")}
    assert 0 < counts["lost /burst"] <= missing
    assert _info(bag_dir)["lost"] == {"/burst": missing}
    text = subprocess.run([sys.executable, "-m", "cablelab.cli", "info", str(bag_dir)],
                          capture_output=True, text=True, timeout=120).stdout
    assert f"lost {missing} samples of /burst" in text


def test_info_reads_the_lost_counts_from_the_bag_metadata(tmp_path, capsys):
    """metadata.yaml custom_data `cablelab.lost.<topic>` round trip (BagWriter -> rosbags ->
    recorder_lost / info); a bag without them reports nothing; a non-number is skipped."""
    from cablelab.bags import BagWriter, bag_info
    from cablelab.cli import main

    def bag(name, custom):
        with BagWriter(tmp_path / name) as w:
            w.write_joint_states("/a/joint_states", [0.0, 0.001], ["j"], position=[[0.0], [1.0]])
            for k, v in custom.items():
                w.set_custom_data(k, v)
        return tmp_path / name

    lossy = bag("lossy", {"cablelab.lost./a/joint_states": "12", "cablelab.lost./clock": "0",
                          "cablelab.lost./b": "many", "other.key": "3"})
    assert recorder_lost(lossy) == {"/a/joint_states": 12, "/clock": 0}
    assert recorder_lost(lossy / "lossy.mcap") == {"/a/joint_states": 12, "/clock": 0}
    assert bag_info(lossy)["lost"] == {"/a/joint_states": 12, "/clock": 0}
    assert main(["info", str(lossy)]) == 0
    assert "warning:  the recorder lost 12 samples of /a/joint_states" in capsys.readouterr().out
    clean = bag("clean", {"cablelab.lost./a/joint_states": "0"})
    assert main(["info", str(clean)]) == 0
    assert "lost:     0 samples (recorder checked 1 topics)" in capsys.readouterr().out
    plain = bag("plain", {})
    assert recorder_lost(plain) is None and "lost" not in bag_info(plain)
