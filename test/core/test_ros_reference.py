"""A controller's played reference (cablelab/ros/reference.py) and the reference/joint-state
helpers of convert.py, without a running ROS graph: the oracle is the trajectory as a closed form
of the time since the first state, and a bag written with the same samples."""
import numpy as np
import pytest

from cablelab.ros import convert
from cablelab.ros.reference import ReferencePlayer, reference_bag_param

JOINTS = ["slew", "luff", "hoist"]


class FakeNode:
    def __init__(self):
        self.sent = []

    def create_publisher(self, _type, topic, _qos):
        self.topic = topic
        return type("Pub", (), {"publish": lambda _self, m: self.sent.append(m)})()


def sine(t, q0):
    w = 2 * np.pi * 0.5
    s = np.sin(w * t)[:, None] * np.array([0.1, 0.2, 0.3])
    return q0 + s, w * np.cos(w * t)[:, None] * np.array([0.1, 0.2, 0.3]), -w * w * s


def test_the_player_starts_at_the_first_state_and_publishes_what_it_plays():
    node = FakeNode()
    p = ReferencePlayer(node, "/crane/reference", JOINTS, sine)
    q0 = np.array([0.0, 0.5, 0.6])
    for k, t in enumerate(12.0 + 0.1 * np.arange(5)):
        q, qd, qdd = p(t, q0 + k)                     # q0: the first state's, not the later ones
        want = sine(np.array([t - 12.0]), q0)
        np.testing.assert_allclose(np.stack([q, qd, qdd]), np.stack([w[0] for w in want]), atol=1e-12)
        ts, names, mq, mqd, mqdd = convert.joint_trajectory_point(node.sent[-1])
        assert ts == pytest.approx(t) and names == JOINTS and node.topic == "/crane/reference"
        np.testing.assert_array_equal(np.stack([mq, mqd, mqdd]), np.stack([q, qd, qdd]))
    assert "/crane/reference" in reference_bag_param("/crane/reference").description


def test_a_bag_plays_its_samples_from_the_first_state_on(tmp_path):
    from cablelab.bags import BagWriter

    t = 100.0 + 0.01 * np.arange(201)
    q, qd, qdd = sine(t - t[0], np.zeros(3))
    with BagWriter(tmp_path / "ref") as w:
        w.write_joint_trajectory("/crane/reference", t, JOINTS, q, qd, qdd)
    node = FakeNode()
    p = ReferencePlayer.from_bag(node, str(tmp_path / "ref"), "/crane/reference", JOINTS)
    p(5.0, np.ones(3))
    got = p(5.5, np.ones(3))                          # 0.5 s in: the bag's sample 50
    np.testing.assert_allclose(np.stack(got), np.stack([q[50], qd[50], qdd[50]]), atol=1e-9)
    got = p(50.0, np.ones(3))                         # past its end: held at the last sample
    np.testing.assert_allclose(got[0], q[-1], atol=1e-12)


def test_a_platform_pose_bag_is_played_and_published_as_a_pose_reference(tmp_path):
    """The CDPR's designed reference: a MultiDOFJointTrajectory bag played from the first state
    on, each sample published as the platform's pose reference (orientation identity)."""
    from cablelab.bags import BagWriter

    t = 10.0 + 0.01 * np.arange(101)
    q, qd, qdd = sine(t - t[0], np.array([0.0, 0.0, 1.0]))
    level = np.tile([0.0, 0.0, 0.0, 1.0], (len(t), 1))
    with BagWriter(tmp_path / "ref") as w:
        w.write_multidof_trajectory("/cdpr/reference", t, q, level, qd, None, qdd)
    node = FakeNode()
    p = ReferencePlayer.from_bag(node, str(tmp_path / "ref"), "/cdpr/reference", ("x", "y", "z"), platform=True)
    p(3.0, ())
    got = p(3.25, ())                                 # 0.25 s in: the bag's sample 25
    np.testing.assert_allclose(np.stack(got), np.stack([q[25], qd[25], qdd[25]]), atol=1e-9)
    r = convert.multidof_arrays(node.sent[-1])
    assert r["t"] == pytest.approx(3.25) and node.topic == "/cdpr/reference"
    np.testing.assert_allclose(r["position"], q[25], atol=1e-9)
    np.testing.assert_allclose(r["linear_velocity"], qd[25], atol=1e-9)
    np.testing.assert_allclose(r["linear_acceleration"], qdd[25], atol=1e-9)
    np.testing.assert_allclose(r["quaternion"], [0.0, 0.0, 0.0, 1.0])


def test_reference_point_and_named_positions():
    msg = convert.joint_trajectory_msg(1.0, JOINTS, [1.0, 2.0, 3.0], [0.1, 0.2], None)
    q, qd, qdd = convert.reference_point(msg, JOINTS)
    assert list(q) == [1, 2, 3] and not qd.any() and not qdd.any()   # wrong length / missing: zeros
    assert convert.reference_point(msg, ["slew", "luff"]) is None
    assert convert.reference_point(convert.joint_trajectory_msg(1.0, JOINTS, [])) is None
    js = convert.joint_state_msg(0.0, ["theta2", "x", "theta1"], [2.0, 9.0, 1.0])
    assert list(convert.named_positions(js, ("theta1", "theta2"))) == [1.0, 2.0]
    assert convert.named_positions(js, ("theta1", "theta3")) is None
