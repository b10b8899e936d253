"""The simulators of the axis, the leg, the suspended platform and any MuJoCo model publish their
3D view (real processes over DDS): recorded beside the simulator's own truth topic, each
MarkerArray draws the machine at the truth of its stamp (axis: the link's load at the true joint
angle; leg: the body at the true height; suspended: CRANEbot's rope ending at the platform's
attachment point; mjcf, the four-cable camera robot: its carriage box at the true slide joints,
at (0, 0, 3) m when they are 0)."""
import sys
import time

import numpy as np
import pytest
from rosbags.typesys import Stores, get_typestore

TS = get_typestore(Stores.ROS2_JAZZY)
AXIS = "plant: axis\naxis:\n  joint_type: revolute\n  inertia: 2.0\n  gravity_moment: 1.0\n"


def _axis(by, bag, j):
    q = bag.joint_state("/axis/ground_truth/joint_states", ["joint"]).position[j, 0]
    p = by["load"].pose.position
    return np.array([p.x, p.y, p.z]), np.array([-np.sin(q), 0.0, -np.cos(q)])   # c = min(1, 0.5 M / m c) = 1 m


def _leg(by, bag, j):
    z = bag.joint_state("/leg/ground_truth/state", ["height"]).position[j, 0]
    p = by["body"].pose.position
    return np.array([p.x, p.y, p.z]), np.array([0.0, 0.0, z])


def _suspended(by, bag, j):
    pose = bag.pose("/suspended/platform_pose")
    end = by["cables"].points[1]
    return np.array([end.x, end.y, end.z]), pose.position[j]


def _mjcf(by, bag, j):
    xyz = bag.joint_state("/mjcf/ground_truth/joint_states", ["x", "y", "z"]).position[j]
    p = by["geoms/box"].pose.position
    return np.array([p.x, p.y, p.z]), np.array([0.0, 0.0, 3.0]) + xyz


CASES = {
    "axis": ({"markers_rate": 30.0}, "/axis/ground_truth/joint_states", _axis),
    "leg": ({"rate": 200.0, "markers_rate": 30.0}, "/leg/ground_truth/state", _leg),
    "suspended": ({"variant": "cranebot", "start_swing_x": 0.2, "markers_rate": 30.0},
                  "/suspended/platform_pose", _suspended),
    "mjcf": ({"rate": 100.0, "markers_rate": 30.0}, "/mjcf/ground_truth/joint_states", _mjcf),
}


@pytest.mark.parametrize("plant", sorted(CASES))
def test_simulator_publishes_the_machine_at_its_truth(plant, launcher, tmp_path):
    from cablelab.bags import open_bag

    params, truth, check = CASES[plant]
    if plant == "axis":                       # a revolute axis with a gravity load (a 1 m link)
        (tmp_path / "axis.yaml").write_text(AXIS)
        params = {**params, "description": str(tmp_path / "axis.yaml")}
    if plant == "mjcf":                       # the four-cable camera robot (spatial tendons)
        from cablelab.plants.mjcf.examples import CABLECAM
        from cablelab.plants.mjcf.sim import description_yaml

        (tmp_path / "cam.yaml").write_text(description_yaml(
            CABLECAM.read_text(), tendons=[f"cable_{i}" for i in range(1, 5)], payload_body="carriage"))
        params = {**params, "description": str(tmp_path / "cam.yaml")}
    bag_dir = tmp_path / "markers"
    launcher.start("recorder", [sys.executable, "-m", "cablelab.cli", "record", "-o", bag_dir, "--quiet",
                                "--topics", f"/{plant}/markers,{truth}"])
    launcher.node("sim", "cable_sim_node", plant, {**params, "wait_for_subscribers": 1})
    deadline = time.monotonic() + 15          # ~450 arrays at 30 Hz of wall time; 20 suffice
    while launcher.procs["sim"].alive() and time.monotonic() < deadline:
        time.sleep(0.5)
    time.sleep(1.0)
    launcher.stop_all()
    bag = open_bag(bag_dir)
    series = bag.pose(truth) if truth.endswith("pose") else bag.joint_state(truth)
    t_ns, raws = bag.raw(f"/{plant}/markers")
    assert len(raws) >= 20
    matched = 0
    for raw in raws:
        msg = TS.deserialize_cdr(raw, "visualization_msgs/msg/MarkerArray")
        assert all(m.header.frame_id == "world" for m in msg.markers)
        stamp = msg.markers[0].header.stamp.sec + 1e-9 * msg.markers[0].header.stamp.nanosec
        j = int(np.argmin(np.abs(series.t - stamp)))
        if abs(series.t[j] - stamp) > 1e-6:
            continue
        matched += 1
        by = {m.ns: m for m in msg.markers}
        by.update({f"{m.ns}/box": m for m in msg.markers if m.type == 1})     # (CUBE)
        got, want = check(by, bag, j)
        np.testing.assert_allclose(got, want, atol=1e-6)
    assert matched >= 10
