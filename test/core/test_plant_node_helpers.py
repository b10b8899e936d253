"""What PlantNode gives every plant's node (cablelab/ros/plant_node.py), in-process: messages read
as serialised bytes equal rclpy's own message objects read by cablelab.ros.convert (the second
implementation), bytes that are not the message are one rejected input; polled subscriptions
leave the executor's wait set and wait queued until taken; a simulator's command input and a
controller's played reference are wired as the node says."""
from __future__ import annotations

import numpy as np
import pytest


@pytest.fixture
def node(domain_id):
    import rclpy

    from cablelab.ros.plant_node import PlantNode

    rclpy.init(domain_id=domain_id)
    n = PlantNode("helpers_test")
    try:
        yield n
    finally:
        n.destroy_node()
        rclpy.try_shutdown()


def test_decode_raw_equals_the_message_objects_and_rejects_junk(node):
    from rclpy.serialization import serialize_message
    from sensor_msgs.msg import JointState
    from trajectory_msgs.msg import MultiDOFJointTrajectory

    from cablelab.ros import convert

    node.inputs.add("joint_states", timeout=1.0)
    node.inputs.add("reference", timeout=1.0)
    js = convert.joint_state_msg(12.345, ["winch_1", "winch_2"], [1.0, -2.0], [0.5, 0.25], [3.0, 4.0])
    for msg in (js, serialize_message(js)):
        t, names, q, qd, eff = node.decode_raw("joint_states", JointState, msg)
        want = convert.joint_state_arrays(js)
        assert t == pytest.approx(want[0], abs=1e-9) and names == want[1]
        for got, ref in zip((q, qd, eff), want[2:]):
            np.testing.assert_array_equal(got, ref)
    ref = convert.multidof_msg(2.5, [0.1, 0.2, 0.3], [0, 0, 0, 1.0], [1.0, 0, 0], None, [0, 0, -1.0], None)
    r = node.decode_raw("reference", MultiDOFJointTrajectory, serialize_message(ref))
    np.testing.assert_allclose(r["position"], [0.1, 0.2, 0.3])
    np.testing.assert_allclose(r["linear_acceleration"], [0.0, 0.0, -1.0])
    assert r["t"] == pytest.approx(2.5)
    assert node.decode_raw("joint_states", JointState, b"\x00\x01junk") is None
    assert node.inputs.inputs["joint_states"].rejected == 1 and node.inputs.inputs["reference"].rejected == 0


def test_polled_subscriptions_wait_until_taken(node):
    from std_msgs.msg import Float64MultiArray

    from cablelab.ros.qos import stream_qos

    got = []
    sub = node.subscribe(Float64MultiArray, "/helpers_test/a", got.append, stream_qos(), polled=True)
    plain = node.subscribe(Float64MultiArray, "/helpers_test/b", got.append, stream_qos())
    assert node.polled == [sub] and sub in node._polled_subscriptions and plain not in node.polled
    assert node.take_polled() == 0 and node.take_polled(newest=True) == 0 and got == []
    import time

    pub = node.create_publisher(Float64MultiArray, "/helpers_test/a", stream_qos())
    deadline = time.monotonic() + 30.0          # (discovery on a busy machine)
    while not got and time.monotonic() < deadline:
        pub.publish(Float64MultiArray(data=[7.0]))
        time.sleep(0.05)
        node.take_polled()                      # nothing spins this node: only the take delivers
    assert got and all(list(m.data) == [7.0] for m in got)


def test_command_input_and_played_reference(node, tmp_path):
    from std_msgs.msg import Float64MultiArray

    from cablelab.ros.qos import stream_qos

    commands = []
    node.on_command = commands.append
    sub = node.command_input("/helpers_test/effort_commands", 3, 0.25, stream_qos(1), polled=True)
    spec = node.inputs.inputs["effort_commands"]
    assert sub.topic_name == "/helpers_test/effort_commands" and sub.msg_type is Float64MultiArray
    assert spec.length == 3 and spec.timeout == 0.25 and node.polled == [sub]
    sub.callback(Float64MultiArray(data=[1.0, 2.0, 3.0]))
    assert commands[0].data.tolist() == [1.0, 2.0, 3.0]
    assert node.play_reference("", "/helpers_test/reference", ["j"]) is None      # follows the topic
    player = node.play_reference("", "/helpers_test/reference", ["j"],
                                 lambda tt, q0: (q0 + tt[:, None], np.ones((len(tt), 1)), np.zeros((len(tt), 1))))
    assert player.pub.topic_name == "/helpers_test/reference"
    q, qd, _ = player(3.0, np.array([0.5]))          # time starts at the first state
    np.testing.assert_allclose([q[0], qd[0]], [0.5, 1.0])
    q, _, _ = player(3.25, np.array([9.0]))
    np.testing.assert_allclose(q[0], 0.75)
