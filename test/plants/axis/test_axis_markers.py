"""The single axis in 3D (visualization_msgs/MarkerArray): the carriage and the load sit where
the simulator's own MuJoCo model puts its body at that joint position (geom_xpos after
mj_forward), decoded from the message bytes; the overlay bag of the EMPS recording carries the
markers at 30 Hz with the carriage at the recorded position of each stamp."""
from pathlib import Path

import mujoco
import numpy as np
from hypothesis import given, settings, strategies as st
from rosbags.typesys import Stores, get_typestore

from cablelab.description import load_description
from cablelab.markers import MarkerEncoder
from cablelab.plants.axis.markers import LINK, axis_markers
from cablelab.plants.axis.sim import AxisSim, AxisTruth

TS = get_typestore(Stores.ROS2_JAZZY)
ROOT = Path(__file__).resolve().parents[3]


def _decoded(frame):
    raw = MarkerEncoder(frame).encode([2.0], [frame])[0]
    msgs = TS.deserialize_cdr(raw, "visualization_msgs/msg/MarkerArray").markers
    assert all(m.header.frame_id == "world" for m in msgs)
    return {m.ns: m for m in msgs}


def _sim_at(desc, inertia, q):
    sim = AxisSim(desc, AxisTruth(inertia=inertia))
    sim.data.qpos[0] = q
    mujoco.mj_forward(sim.model, sim.data)
    return sim


def _xyz(p):
    return np.array([p.x, p.y, p.z])


@settings(max_examples=20, deadline=None)
@given(q=st.floats(-3.0, 3.0), inertia=st.floats(0.1, 20.0),
       gm=st.one_of(st.just(0.0), st.floats(0.05, 5.0)),      # (the simulator needs m = gm / c > 1e-15 kg)
       prismatic=st.booleans())
def test_machine_is_where_the_simulator_puts_it(q, inertia, gm, prismatic):
    kind = "prismatic" if prismatic else "revolute"
    desc = load_description(f"plant: axis\naxis:\n  joint_type: {kind}\n  inertia: {inertia!r}\n"
                            + ("" if prismatic else f"  gravity_moment: {gm!r}\n"))
    sim = _sim_at(desc, inertia, q)
    by = _decoded(axis_markers(desc, q, inertia))
    if prismatic:
        np.testing.assert_allclose(_xyz(by["carriage"].pose.position), sim.data.geom_xpos[0], atol=1e-12)
        np.testing.assert_allclose([by["carriage"].scale.x] * 3, 2 * sim.model.geom_size[0], atol=1e-12)
        return
    pts = np.array([_xyz(p) for p in by["link"].points])
    np.testing.assert_allclose(pts[0], sim.data.xpos[1], atol=1e-12)           # the hinge
    if gm > 0:           # the link ends at the simulator's point mass, where the load is drawn
        np.testing.assert_allclose(pts[1], sim.data.geom_xpos[0], atol=1e-9)
        np.testing.assert_allclose(_xyz(by["load"].pose.position), sim.data.geom_xpos[0], atol=1e-9)
    else:                # no gravity load: a 0.3 m link along the body's -z
        np.testing.assert_allclose(pts[1], -LINK * sim.data.xmat[1].reshape(3, 3)[:, 2], atol=1e-9)


def test_overlay_bag_of_the_emps_recording_carries_the_carriage(tmp_path):
    from cablelab.bags import open_bag
    from cablelab.cli import main

    out = tmp_path / "ov"
    assert main(["compare", str(ROOT / "bags" / "emps"), "--out", str(out), "--json"]) == 0
    bag = open_bag(out)
    js = bag.joint_state("/axis/joint_states", ["joint"])
    t_ns, raws = bag.raw("/axis/markers")
    t = np.asarray(t_ns) * 1e-9
    assert bag.topics["/axis/markers"] == "visualization_msgs/msg/MarkerArray"
    assert 25.0 < len(t) / (t[-1] - t[0]) < 35.0          # about 30 Hz
    moved = set()
    for k in range(0, len(raws), max(1, len(raws) // 25)):
        msg = TS.deserialize_cdr(raws[k], "visualization_msgs/msg/MarkerArray")
        car = {m.ns: m for m in msg.markers}["carriage"]
        stamp = car.header.stamp.sec + 1e-9 * car.header.stamp.nanosec
        j = int(np.argmin(np.abs(js.t - stamp)))
        assert abs(js.t[j] - stamp) < 1e-6
        np.testing.assert_allclose(_xyz(car.pose.position), [js.position[j, 0], 0.0, 0.0], atol=1e-12)
        moved.add(round(js.position[j, 0], 3))
    assert len(moved) > 3                                 # the carriage travels along the recording
