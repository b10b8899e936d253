"""The suspended estimator node in-process (rclpy): poses in, swing estimate out, equal to the
library's SwingEstimator (second implementation path: the batch formula), bad samples held and
reported."""
import time

import numpy as np
import pytest


@pytest.fixture
def ros_context(domain_id):
    import rclpy

    rclpy.init(domain_id=domain_id)
    yield
    rclpy.try_shutdown()


def test_estimator_node_publishes_swing_and_survives_nan(ros_context):
    import rclpy
    from rclpy.executors import SingleThreadedExecutor
    from sensor_msgs.msg import JointState
    from geometry_msgs.msg import PoseStamped

    from cablelab.plants.suspended.nodes import make_node
    from cablelab.plants.suspended.params import parameter_set
    from cablelab.plants.suspended.swing import swing_from_pose
    from cablelab.ros import convert
    from cablelab.ros.qos import catch_up_qos, publisher_qos

    node = make_node("estimator")
    peer = rclpy.create_node("peer")
    got = []
    peer.create_subscription(JointState, "/suspended/swing_estimate", lambda m: got.append(m), catch_up_qos())
    pub = peer.create_publisher(PoseStamped, "/suspended/platform_pose", publisher_qos())
    ex = SingleThreadedExecutor()
    ex.add_node(node)
    ex.add_node(peer)
    S = np.array(parameter_set("licas").S)
    t = 1.0 + np.arange(60) * 0.01
    th = 0.1 * np.sin(3.1 * t)
    pos = S + np.stack([0 * t, np.sin(th), -np.cos(th)], 1)
    quat = np.stack([np.cos(0.05 * t), 0 * t, 0 * t, np.sin(0.05 * t)], 1)     # w x y z
    deadline = time.monotonic() + 10
    while node.count_subscribers("/suspended/platform_pose") == 0 or pub.get_subscription_count() == 0:
        ex.spin_once(timeout_sec=0.05)
        assert time.monotonic() < deadline
    for i in range(len(t)):
        pub.publish(convert.pose_msg(t[i], pos[i], quat[i, [1, 2, 3, 0]]))
        if i == 30:
            pub.publish(convert.pose_msg(t[i] + 0.005, [np.nan, 0, 0], [0, 0, 0, 1.0]))
        ex.spin_once(timeout_sec=0.01)
    deadline = time.monotonic() + 10
    while len(got) < len(t) and time.monotonic() < deadline:
        ex.spin_once(timeout_sec=0.05)
    assert len(got) == len(t)
    ref = swing_from_pose(pos, quat, S)
    sx = np.array([m.position[0] for m in got])
    assert np.abs(sx - ref["swing_x"]).max() < 1e-12
    assert node.rejected == 1
    level, msg, _ = node.status()
    assert level >= 1 and "NaN" in msg
    ex.shutdown()
    node.destroy_node()
    peer.destroy_node()


def test_sim_node_to_estimator_node_chain(ros_context):
    import rclpy
    from rclpy.executors import SingleThreadedExecutor
    from sensor_msgs.msg import JointState
    from geometry_msgs.msg import PoseStamped
    from trajectory_msgs.msg import JointTrajectory

    from cablelab.plants.suspended.nodes import make_node
    from cablelab.plants.suspended.params import parameter_set
    from cablelab.ros import convert
    from cablelab.ros.qos import catch_up_qos, publisher_qos

    # LiCAS virtual-joint model (defaults), started displaced via a parameter override
    sim = make_node_with(make_node, "sim", {"start_swing_x": 0.1})
    est = make_node("estimator")
    peer = rclpy.create_node("peer2")
    poses, truth, estim = [], [], []
    peer.create_subscription(PoseStamped, "/suspended/platform_pose", poses.append, catch_up_qos())
    peer.create_subscription(JointState, "/suspended/ground_truth/swing", truth.append, catch_up_qos())
    peer.create_subscription(JointState, "/suspended/swing_estimate", estim.append, catch_up_qos())
    ref = peer.create_publisher(JointTrajectory, "/suspended/reference", publisher_qos())
    ex = SingleThreadedExecutor()
    for n in (sim, est, peer):
        ex.add_node(n)
    deadline = time.monotonic() + 3.0
    while time.monotonic() < deadline:
        ex.spin_once(timeout_sec=0.01)
    ref.publish(convert.joint_trajectory_msg(0.0, ["bogus"], [0.0]))
    for _ in range(20):
        ex.spin_once(timeout_sec=0.01)
    assert len(poses) > 50 and len(truth) > 50 and len(estim) > 30
    p = parameter_set("licas")
    d = np.array([[m.pose.position.x, m.pose.position.y, m.pose.position.z] for m in poses]) - p.S
    assert np.allclose(np.linalg.norm(d, axis=1), p.L, atol=1e-9)          # on the cable sphere
    sx_truth = {round(convert.from_stamp(m.header.stamp), 6): m.position[0] for m in truth}
    pairs = [(m.position[0], sx_truth[round(convert.from_stamp(m.header.stamp), 6)]) for m in estim
             if round(convert.from_stamp(m.header.stamp), 6) in sx_truth]
    assert len(pairs) > 30 and max(abs(a - b) for a, b in pairs) < 1e-9
    assert max(abs(b) for _, b in pairs) == pytest.approx(0.1, abs=0.01)
    assert sim.inputs.status(time.monotonic())[0] >= 1                      # bad reference reported
    ex.shutdown()
    for n in (sim, est, peer):
        n.destroy_node()


def make_node_with(make_node, role, overrides):
    """A node with ROS parameter overrides (as --ros-args -p would give)."""
    import rclpy.node as rn
    from rclpy.parameter import Parameter

    orig = rn.Node.__init__

    def init(self, name, *a, **kw):
        kw.setdefault("parameter_overrides", [Parameter(k, value=v) for k, v in overrides.items()])
        orig(self, name, *a, **kw)

    rn.Node.__init__ = init
    try:
        return make_node(role)
    finally:
        rn.Node.__init__ = orig
