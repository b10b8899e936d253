"""The boom crane in 3D: the boom line ends at the boom tip and the rope at the payload of the
contract's kinematics (CONTRACT sec. 2, written out here), decoded from the MarkerArray bytes."""
import numpy as np
from hypothesis import given, settings, strategies as st
from rosbags.typesys import Stores, get_typestore

from cablelab.description import load_description
from cablelab.markers import MarkerEncoder
from cablelab.plants.crane.markers import state_markers

DESC = load_description("plant: crane\ncrane:\n  boom_length: 1.2\n  counterbalance: {mass: 2.0, distance: 0.3}\n")
TS = get_typestore(Stores.ROS2_JAZZY)


@settings(max_examples=20, deadline=None)
@given(a=st.floats(-3.0, 3.0), b=st.floats(-0.5, 1.2), d=st.floats(0.2, 1.5),
       t1=st.floats(-0.4, 0.4), t2=st.floats(-0.4, 0.4))
def test_boom_and_rope_end_at_the_contract_positions(a, b, d, t1, t2):
    lb = 1.2
    tip = np.array([lb * np.cos(b) * np.cos(a), lb * np.cos(b) * np.sin(a), lb * np.sin(b)])
    v = d * np.array([np.sin(t2), np.sin(t1) * np.cos(t2), -np.cos(t1) * np.cos(t2)])
    payload = tip + np.array([np.cos(a) * v[0] - np.sin(a) * v[1], np.sin(a) * v[0] + np.cos(a) * v[1], v[2]])
    frame = state_markers(DESC, [a, b, d, t1, t2])
    msg = TS.deserialize_cdr(MarkerEncoder(frame).encode([3.0], [frame])[0], "visualization_msgs/msg/MarkerArray")
    by = {m.ns: m for m in msg.markers}
    pts = {ns: np.array([[p.x, p.y, p.z] for p in m.points]) for ns, m in by.items()}
    np.testing.assert_allclose(pts["boom"], [[0, 0, 0], tip], atol=1e-9)
    np.testing.assert_allclose(pts["rope"], [tip, payload], atol=1e-9)
    p = by["payload"].pose.position
    np.testing.assert_allclose([p.x, p.y, p.z], payload, atol=1e-9)
    c = by["counterbalance"].pose.position           # 0.3 m behind the pivot, against the boom
    np.testing.assert_allclose([c.x, c.y, c.z], [-0.3 * np.cos(a), -0.3 * np.sin(a), 0.0], atol=1e-9)
    assert all(m.header.frame_id == "world" for m in msg.markers)
