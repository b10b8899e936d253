"""The reference a controller follows (:class:`cablelab.ros.reference.FollowedReference`) and a
simulator's status values, without a running ROS graph: a topic's point is used while fresh and
only when it names the joints (or any names, when allowed), a built-in trajectory is played from
the first state or at the state stamps themselves (``absolute``) and published, and the
``reference`` input is required only when the topic is followed. Oracle: the trajectory's closed
form, the input monitor's own counts."""
import time

import numpy as np
import pytest

from cablelab.ros import convert
from cablelab.ros.inputs import InputMonitor
from cablelab.ros.reference import FollowedReference
from cablelab.ros.status import sim_values

JOINTS = ["slew", "luff", "hoist"]


class FakeNode:
    """What FollowedReference uses of a PlantNode: inputs, accept, publishers, subscriptions."""

    def __init__(self):
        self.inputs, self.sent, self.subs = InputMonitor(), [], []

    def accept(self, name, values):
        return self.inputs.accept(name, values, time.monotonic())

    def create_publisher(self, _type, topic, _qos):
        return type("Pub", (), {"publish": lambda _self, m: self.sent.append((topic, m))})()

    def create_subscription(self, _type, topic, callback, _qos):
        self.subs.append((topic, callback))


def ramp(t, q0):
    t = np.asarray(t, float)[:, None]
    return q0 + 0.1 * t, 0.1 + 0 * t, 0 * t


def test_topic_point_is_used_while_fresh_and_when_it_names_the_joints():
    node = FakeNode()
    ref = FollowedReference(node, "/crane/reference", JOINTS, timeout=0.5)
    assert ref.source == "topic" and node.subs[0][0] == "/crane/reference"
    assert "reference" in node.inputs.required
    assert ref(1.0, np.zeros(3)) is None                                  # nothing yet
    node.subs[0][1](convert.joint_trajectory_msg(1.0, ["a", "b", "c"], [1.0, 2.0, 3.0]))
    assert ref(1.0, np.zeros(3)) is None and node.inputs.inputs["reference"].rejected == 1
    node.subs[0][1](convert.joint_trajectory_msg(1.0, JOINTS, [1.0, 2.0, 3.0], [0.1, 0.2, 0.3]))
    q, qd, qdd = ref(1.0, np.zeros(3))
    np.testing.assert_array_equal(q, [1, 2, 3])
    np.testing.assert_array_equal(qd, [0.1, 0.2, 0.3])
    np.testing.assert_array_equal(qdd, [0, 0, 0])                         # missing: zeros
    node.inputs.inputs["reference"].last_time -= 1.0                       # stale
    assert ref(1.1, np.zeros(3)) is None
    other = FollowedReference(FakeNode(), "/axis/reference", ["joint"], any_names=True)
    other.on_message(convert.joint_trajectory_msg(1.0, ["whatever"], [0.5]))
    assert other(1.0, [0.0])[0][0] == 0.5


@pytest.mark.parametrize("absolute", [False, True])
def test_builtin_trajectory_is_played_and_published(absolute):
    node = FakeNode()
    ref = FollowedReference(node, "/crane/reference", JOINTS, trajectory=ramp, absolute=absolute)
    assert ref.source == "builtin" and not node.subs and "reference" not in node.inputs.required
    q0 = np.array([0.0, 0.5, 0.6])
    for t in (10.0, 10.5, 11.0):
        q, qd, _ = ref(t, q0 + 1.0 if t > 10.0 else q0)                   # q0: the first state's
        np.testing.assert_allclose(q, q0 + 0.1 * (t if absolute else t - 10.0), atol=1e-12)
        topic, msg = node.sent[-1]
        ts, names, mq, _, _ = convert.joint_trajectory_point(msg)
        assert topic == "/crane/reference" and ts == pytest.approx(t) and names == JOINTS
        np.testing.assert_array_equal(mq, q)


def test_simulator_status_values():
    class Lock:
        stale_answers = 3

    assert sim_values({}, 1.23456, Lock()) == {"sim time s": "1.235", "stale answers ignored (lock-step)": "3"}
    assert sim_values({"a": "1"}) == {"a": "1"}
