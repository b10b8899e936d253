"""The suspended estimator node in-process (rclpy): poses in, swing estimate out, equal to the
library's SwingEstimator (second implementation path: the batch formula), bad samples held and
reported."""
import time

import numpy as np
import pytest


def test_estimator_node_publishes_swing_and_survives_nan(ros_context):
    import rclpy
    from rclpy.executors import SingleThreadedExecutor
    from sensor_msgs.msg import JointState
    from geometry_msgs.msg import PoseStamped

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
    assert node.est.held == 1
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


def make_node(role):
    """The suspended plant's node of ``role`` (its module's ``make_node()``)."""
    from cablelab.ros.runner import node_module

    return node_module("suspended", role).make_node()


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


def test_controller_node_law_sway_offset_and_bad_input(ros_context):
    """The controller node answers each joint state with the library law (PD + gravity under the
    platform attitude + sway offset from the swing estimate), and ignores NaN / wrong-length
    states. (A closed loop through the in-process executor is not tested: the LiCAS joint 3 has
    k_d / I ~ 1000 1/s, so the executor's multi-millisecond answer delay destabilises it; the
    delay-free loop is A10.)"""
    import rclpy
    from rclpy.executors import SingleThreadedExecutor
    from geometry_msgs.msg import PoseStamped
    from sensor_msgs.msg import JointState
    from std_msgs.msg import Float64MultiArray

    from cablelab.plants.suspended.control import ArmGravity, gains, pd_gravity, sway_offset
    from cablelab.plants.suspended.params import parameter_set
    from cablelab.ros import convert
    from cablelab.ros.qos import catch_up_qos, publisher_qos

    ctl = make_node_with(make_node, "controller", {"sway_damping": 0.3})
    peer = rclpy.create_node("peer3")
    cmds = []
    peer.create_subscription(Float64MultiArray, "/suspended/effort_commands", cmds.append, catch_up_qos())
    pj = peer.create_publisher(JointState, "/suspended/joint_states", publisher_qos())
    pp = peer.create_publisher(PoseStamped, "/suspended/platform_pose", publisher_qos())
    ps = peer.create_publisher(JointState, "/suspended/swing_estimate", publisher_qos())
    ex = SingleThreadedExecutor()
    ex.add_node(ctl)
    ex.add_node(peer)
    deadline = time.monotonic() + 10
    while pj.get_subscription_count() == 0 or ps.get_subscription_count() == 0 or pp.get_subscription_count() == 0:
        ex.spin_once(timeout_sec=0.05)
        assert time.monotonic() < deadline
    p = parameter_set("licas")
    names = [f"left_{i}" for i in range(1, 5)] + [f"right_{i}" for i in range(1, 5)]
    c, s_ = np.cos(0.1), np.sin(0.1)                  # platform rolled 0.1 rad about x
    pp.publish(convert.pose_msg(1.0, [0, 0.1, 0.85], [np.sin(0.05), 0, 0, np.cos(0.05)]))
    ps.publish(convert.joint_state_msg(1.0, ["swing_x", "swing_y", "yaw", "r_x", "r_y"],
                                       [0.1, 0, 0, 0, 0.1], [0, 0, 0, 0, 0.2]))
    for _ in range(20):
        ex.spin_once(timeout_sec=0.01)
    q = np.array([0.1, 0.2, -0.1, 0.0, 0.05, -0.2, 0.1, 0.3])
    qd = np.full(8, 0.1)
    pj.publish(convert.joint_state_msg(1.01, names, [np.nan] * 8, qd))     # rejected
    pj.publish(convert.joint_state_msg(1.01, names[:3], q[:3], qd[:3]))     # rejected
    pj.publish(convert.joint_state_msg(1.01, names, q, qd))
    deadline = time.monotonic() + 5
    while not cmds and time.monotonic() < deadline:
        ex.spin_once(timeout_sec=0.02)
    for _ in range(10):
        ex.spin_once(timeout_sec=0.01)
    assert len(cmds) == 1
    R = np.array([[1, 0, 0], [0, c, -s_], [0, s_, c]])
    kp, kd, lim = gains(p)
    ref = np.zeros(8)
    ref[1] = ref[5] = sway_offset(0.2, 0.3, 0.01)                            # -0.06 rad
    want = pd_gravity(q, qd, ref, 0, kp, kd, ArmGravity(p).torque(q, R), lim)
    assert np.allclose(np.array(cmds[0].data), want, atol=1e-9)
    assert ctl.inputs.status(time.monotonic())[0] >= 1                      # bad states reported
    ex.shutdown()
    ctl.destroy_node()
    peer.destroy_node()


def test_estimator_node_takes_yaw_rate_from_the_imu_and_reports_a_bad_one(ros_context):
    """Simulator (virtual model, yawing, IMU on) -> estimator: the yaw rate comes from the gyro
    (no low-pass lag): against the simulator's truth yaw differentiated over 20 ms it is within
    0.01 rad/s where the 0.05 s low-pass of the pose difference lags by ~0.2 rad/s. A NaN IMU
    message is held and reported on /diagnostics."""
    import rclpy
    from rclpy.executors import SingleThreadedExecutor
    from sensor_msgs.msg import Imu, JointState

    from cablelab.ros import convert
    from cablelab.ros.qos import catch_up_qos, publisher_qos

    sim = make_node_with(make_node, "sim", {"start_yaw": 0.3})
    est = make_node("estimator")
    peer = rclpy.create_node("peer4")
    truth, estim = [], []
    peer.create_subscription(JointState, "/suspended/ground_truth/swing", truth.append, catch_up_qos())
    peer.create_subscription(JointState, "/suspended/swing_estimate", estim.append, catch_up_qos())
    bad = peer.create_publisher(Imu, "/suspended/imu", publisher_qos())
    ex = SingleThreadedExecutor()
    for n in (sim, est, peer):
        ex.add_node(n)
    deadline = time.monotonic() + 4.0
    while time.monotonic() < deadline:
        ex.spin_once(timeout_sec=0.01)
    assert est.est.from_imu > 30
    st = lambda m: round(convert.from_stamp(m.header.stamp), 6)
    yaw = {st(m): m.position[2] for m in truth}
    ts = np.array(sorted(yaw))
    y = np.array([yaw[k] for k in ts])
    dt = np.median(np.diff(ts))
    rate = {k: (y[i + 1] - y[i - 1]) / (ts[i + 1] - ts[i - 1]) for i, k in enumerate(ts[1:-1], 1)
            if abs(ts[i + 1] - ts[i - 1] - 2 * dt) < 1e-6}
    pairs = np.array([(m.velocity[2], rate[st(m)]) for m in estim if st(m) in rate])
    assert len(pairs) > 30 and np.abs(pairs[:, 1]).max() > 0.5              # it yaws
    assert np.abs(pairs[:, 0] - pairs[:, 1]).max() < 0.01
    bad.publish(convert.imu_msg(sim.sim.t, [np.nan, 0, 0, 1.0], [0, 0, 0]))
    for _ in range(30):
        ex.spin_once(timeout_sec=0.01)
    level, msg, values = est.status()
    assert level >= 1 and "imu" in msg and values["imu rejected"] == "1", (msg, values)
    ex.shutdown()
    for n in (sim, est, peer):
        n.destroy_node()
