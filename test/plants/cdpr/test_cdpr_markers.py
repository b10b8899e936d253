"""The CDPR in 3D (visualization_msgs/MarkerArray): eight cable lines from the exit points A_i
to the anchor points p + R B_i of the current pose. Oracle: the points computed here from the
description's YAML text (not its parsed object) and scipy's rotation, the message decoded by
rosbags; live: the simulator node's markers against its ground-truth pose of the same stamp."""
import sys
import time
from pathlib import Path

import numpy as np
import pytest
import yaml
from hypothesis import given, settings, strategies as st
from rosbags.typesys import Stores, get_typestore
from scipy.spatial.transform import Rotation

from cablelab.markers import LINE_STRIP, Marker, MarkerEncoder, marker_array_cdr
from cablelab.plants.cdpr.markers import cdpr_markers
from cablelab.plants.cdpr.sim import default_description, default_description_path

TS = get_typestore(Stores.ROS2_JAZZY)


def _yaml_points():
    raw = yaml.safe_load(Path(default_description_path()).read_text())["cdpr"]["cables"]
    return np.array([c["exit_point"] for c in raw], float), np.array([c["anchor_point"] for c in raw], float)


def _cables(msg):
    """{id: ((2, 3) end points, rgba)} of the cable lines of a decoded MarkerArray."""
    out = {}
    for m in msg.markers:
        if m.ns == "cables":
            assert m.type == LINE_STRIP and m.header.frame_id == "world" and len(m.points) == 2
            out[m.id] = (np.array([[p.x, p.y, p.z] for p in m.points]), (m.color.r, m.color.g, m.color.b))
    return out


@settings(max_examples=15, deadline=None)
@given(x=st.floats(-1.0, 1.0), y=st.floats(-1.0, 1.0), z=st.floats(0.5, 2.5),
       rv=st.lists(st.floats(-0.3, 0.3), min_size=3, max_size=3),
       ten=st.lists(st.floats(0.0, 3000.0), min_size=8, max_size=8))
def test_cable_lines_end_at_exit_and_anchor_points(x, y, z, rv, ten):
    desc = default_description()
    rot = Rotation.from_rotvec(rv)
    p = np.array([x, y, z])
    A, B = _yaml_points()
    frame = cdpr_markers(desc, p, rot.as_matrix(), np.array(ten))
    for data in (marker_array_cdr(frame, 12.345), MarkerEncoder(frame).encode([12.345], [frame])[0]):
        msg = TS.deserialize_cdr(data, "visualization_msgs/msg/MarkerArray")
        cables = _cables(msg)
        assert sorted(cables) == list(range(1, 9))
        for i in range(8):
            ends, rgb = cables[i + 1]
            np.testing.assert_allclose(ends[0], A[i], atol=1e-12)
            np.testing.assert_allclose(ends[1], p + rot.apply(B[i]), atol=1e-9)
        # colour by tension: the most tensioned cable is the reddest, the least the bluest
        reds = [cables[i + 1][1][0] - cables[i + 1][1][2] for i in range(8)]
        assert reds[int(np.argmax(ten))] == max(reds) and reds[int(np.argmin(ten))] == min(reds)
        assert msg.markers[0].header.stamp.sec == 12 and abs(msg.markers[0].header.stamp.nanosec - 345_000_000) <= 1
        platform = [m for m in msg.markers if m.ns == "platform"][0]
        q = platform.pose.orientation
        np.testing.assert_allclose(Rotation.from_quat([q.x, q.y, q.z, q.w]).as_matrix(), rot.as_matrix(), atol=1e-6)


def test_overlay_bag_of_a_recording_carries_the_markers(tmp_path):
    from cablelab.bags import open_bag
    from cablelab.cli import main

    root = Path(__file__).resolve().parents[3]
    out = tmp_path / "ov"
    assert main(["compare", str(root / "bags" / "cdpr_m1_reference"), "--out", str(out), "--json"]) == 0
    bag = open_bag(out)
    pose = bag.pose("/cdpr/platform_pose")
    t_ns, raws = bag.raw("/cdpr/markers")
    t = np.asarray(t_ns) * 1e-9
    assert 25.0 < len(t) / (t[-1] - t[0]) < 35.0          # about 30 Hz
    A, B = _yaml_points()
    for k in (0, len(raws) // 2, len(raws) - 1):
        msg = TS.deserialize_cdr(raws[k], "visualization_msgs/msg/MarkerArray")
        j = int(np.argmin(np.abs(pose.t - t[k])))
        assert abs(pose.t[j] - t[k]) < 1e-6
        rot = Rotation.from_quat(pose.quaternion[j])
        cables = _cables(msg)
        for i in range(8):
            np.testing.assert_allclose(cables[i + 1][0][1], pose.position[j] + rot.apply(B[i]), atol=1e-9)


def test_simulator_node_publishes_the_machine(launcher, tmp_path):
    """cable_sim_node (real process) publishes /cdpr/markers; recorded beside the ground-truth
    pose, each array's cable lines end at the anchor points of the true pose of its stamp."""
    from cablelab.bags import open_bag

    bag_dir = tmp_path / "markers"
    launcher.start("recorder", [sys.executable, "-m", "cablelab.cli", "record", "-o", bag_dir, "--quiet",
                                "--topics", "/cdpr/markers,/cdpr/ground_truth/pose"])
    launcher.node("sim", "cable_sim_node", "cdpr", {"real_time": True, "rate": 100.0, "duration": 6.0,
                                                    "payload_mass": 100.0, "markers_rate": 30.0,
                                                    "wait_for_subscribers": 1})
    deadline = time.monotonic() + 120
    while launcher.procs["sim"].alive() and time.monotonic() < deadline:
        time.sleep(0.5)
    time.sleep(2.0)
    launcher.stop_all()
    bag = open_bag(bag_dir)
    gt = bag.pose("/cdpr/ground_truth/pose")
    t_ns, raws = bag.raw("/cdpr/markers")
    assert len(raws) >= 30
    A, B = _yaml_points()
    matched = 0
    for ti, raw in zip(np.asarray(t_ns) * 1e-9, raws):
        msg = TS.deserialize_cdr(raw, "visualization_msgs/msg/MarkerArray")
        stamp = msg.markers[0].header.stamp.sec + 1e-9 * msg.markers[0].header.stamp.nanosec
        j = int(np.argmin(np.abs(gt.t - stamp)))
        if abs(gt.t[j] - stamp) > 1e-6:
            continue
        matched += 1
        rot = Rotation.from_quat(gt.quaternion[j])
        cables = _cables(msg)
        assert sorted(cables) == list(range(1, 9))
        for i in range(8):
            np.testing.assert_allclose(cables[i + 1][0][0], A[i], atol=1e-12)
            np.testing.assert_allclose(cables[i + 1][0][1], gt.position[j] + rot.apply(B[i]), atol=1e-6)
    assert matched >= 10


@settings(max_examples=60, deadline=None)
@given(st.integers(1, 100_000), st.sampled_from([0.001, 0.002, 0.005, 0.01, 1.0 / 30.0]))
def test_marker_stamps_are_the_time_to_the_nanosecond(k, dt):
    """A simulator's clock is a sum of steps (k steps of dt: a hair below a whole second when
    the steps add up to one): both serialisers stamp it with the time rounded to the nanosecond
    (oracle: Python's exact integer arithmetic on the float), never a second early."""
    from cablelab import cdr

    t = 0.0
    for _ in range(k % 2000):
        t += dt
    t += (k // 2000) * 1.0
    ns = round(t * 1e9)
    frame = [Marker(1, "box", 0)]
    for data in (marker_array_cdr(frame, t), MarkerEncoder(frame).encode([t], [frame])[0]):
        msg = cdr.typestore().deserialize_cdr(data, "visualization_msgs/msg/MarkerArray")
        stamp = msg.markers[0].header.stamp
        assert stamp.sec * 1_000_000_000 + stamp.nanosec == ns and 0 <= stamp.nanosec < 1_000_000_000
