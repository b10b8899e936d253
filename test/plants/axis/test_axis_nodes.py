"""Node machinery without DDS traffic: axis physics vs closed forms, RLS, input checks, argument
handling, message conversions cross-checked against rclpy's own serialiser, and node adapters
fed bad messages."""
from __future__ import annotations

import subprocess
import sys

import numpy as np
import pytest

from cablelab.description import load_description
from cablelab.errors import CablelabError
from cablelab.plants.axis.control import regressor
from cablelab.plants.axis.sim import AxisSim, AxisTruth
from cablelab.rls import RecursiveLeastSquares
from cablelab.ros.inputs import ERROR, OK, WARN, InputMonitor
from cablelab.ros.runner import split_ros_args

PRISMATIC = load_description("plant: axis\naxis:\n  joint_type: prismatic\n  inertia: 2.0\n")


# ----------------------------------------------------------------------------- axis physics
def test_axis_sim_first_order_velocity_response_matches_closed_form():
    """M v' + Fv v = u from rest: v(t) = u/Fv (1 - exp(-Fv t / M))."""
    M, Fv, u = 2.0, 5.0, 10.0
    sim = AxisSim(PRISMATIC, AxisTruth(inertia=M, viscous=Fv, coulomb=0.0))
    t, v = [], []
    for _ in range(100):
        ti, _q, vi = sim.advance(u, 0.01)
        t.append(ti)
        v.append(vi)
    t, v = np.array(t), np.array(v)
    np.testing.assert_allclose(t[-1], 1.0, atol=1e-9)
    np.testing.assert_allclose(v, u / Fv * (1 - np.exp(-Fv * t / M)), rtol=5e-3, atol=1e-4)


def test_axis_sim_coulomb_friction_terminal_velocity_and_stiction():
    """Steady state (u - Fc)/Fv; below the friction level the load stays put."""
    sim = AxisSim(PRISMATIC, AxisTruth(inertia=2.0, viscous=5.0, coulomb=3.0))
    _, _, v = sim.advance(13.0, 5.0)
    np.testing.assert_allclose(v, (13.0 - 3.0) / 5.0, rtol=0.02)
    stuck = AxisSim(PRISMATIC, AxisTruth(inertia=2.0, viscous=5.0, coulomb=3.0))
    _, q, v = stuck.advance(2.0, 2.0)
    # MuJoCo's frictionloss is a soft constraint: a slow creep, < 1 % of the free motion (0.8 m)
    assert abs(q) < 8e-3 and abs(v) < 4e-3


def test_axis_sim_revolute_pendulum_period():
    """Small oscillations of J q'' = -m c g sin q: period 2 pi sqrt(J / (m c g))."""
    J, mc, g = 0.5, 0.4, 9.81
    desc = load_description(f"plant: axis\ngravity: {g}\naxis:\n  joint_type: revolute\n"
                            f"  inertia: {J}\n  gravity_moment: {mc}\n")
    sim = AxisSim(desc, AxisTruth(inertia=J, viscous=0.0, coulomb=0.0, timestep=0.0005))
    sim.data.qpos[0] = 0.02
    q = np.array([sim.advance(0.0, 0.001)[1] for _ in range(6000)])
    t = np.arange(1, 6001) * 0.001
    up = np.flatnonzero((q[:-1] < 0) & (q[1:] >= 0))
    crossings = t[up] - q[up] * 0.001 / (q[up + 1] - q[up])
    period = np.mean(np.diff(crossings))
    np.testing.assert_allclose(period, 2 * np.pi * np.sqrt(J / (mc * g)), rtol=2e-3)


def test_axis_sim_rejects_bad_parameters():
    with pytest.raises(CablelabError):
        AxisSim(PRISMATIC, AxisTruth(inertia=-1.0))


# ----------------------------------------------------------------------------- RLS
def test_rls_batch_equals_sequential_and_recovers_parameters():
    rng = np.random.default_rng(0)
    theta = np.array([2.0, 5.0, 1.0, 0.3])
    qd = rng.normal(size=400)
    qdd = rng.normal(size=400)
    phi = regressor(qd, qdd)
    y = phi @ theta
    batch = RecursiveLeastSquares(4, lam=0.99)
    batch.update(phi, y)
    seq = RecursiveLeastSquares(4, lam=0.99)
    for i in range(len(y)):
        seq.update(phi[i:i + 1], y[i:i + 1])
    np.testing.assert_allclose(batch.theta, seq.theta, rtol=1e-9)
    np.testing.assert_allclose(batch.theta, theta, rtol=1e-5)
    # least-squares oracle on noisy data without forgetting
    yn = y + rng.normal(scale=0.1, size=len(y))
    rls = RecursiveLeastSquares(4, lam=1.0, p0=1e9)
    rls.update(phi, yn)
    np.testing.assert_allclose(rls.theta, np.linalg.lstsq(phi, yn, rcond=None)[0], rtol=1e-6)
    # NaN rows are skipped
    before = rls.theta.copy()
    rls.update([[np.nan, 1, 1, 1]], [3.0])
    np.testing.assert_array_equal(rls.theta, before)


def test_sine_trajectory_is_the_closed_form_sine_at_the_stamps_as_columns():
    """The built-in reference the controller plays (``reference_source:=sine``): position, rate
    and acceleration of ``offset + A sin(2 pi f t)`` at the state stamps themselves, one column."""
    from cablelab.plants.axis.control import sine_trajectory

    t = np.array([0.0, 0.3, 1.7, 12.25])
    q, qd, qdd = sine_trajectory(0.2, 0.5, 0.1)(t, None)
    assert q.shape == qd.shape == qdd.shape == (4, 1)
    np.testing.assert_allclose(q[:, 0], 0.1 + 0.2 * np.sin(np.pi * t), atol=1e-12)
    np.testing.assert_allclose(qd[:, 0], 0.2 * np.pi * np.cos(np.pi * t), atol=1e-12)
    np.testing.assert_allclose(qdd[:, 0], -0.2 * np.pi ** 2 * np.sin(np.pi * t), atol=1e-12)


# ----------------------------------------------------------------------------- input checks
def test_input_monitor_rejects_nan_wrong_length_and_reports_stale():
    mon = InputMonitor()
    mon.add("cmd", timeout=0.5, length=1)
    mon.add("ref", timeout=0.5, length=3, required=False)
    assert mon.accept("cmd", [1.0], now=10.0)
    assert not mon.accept("cmd", [np.nan], now=10.1)
    assert not mon.accept("cmd", [1.0, 2.0], now=10.1)
    assert not mon.accept("cmd", None, now=10.1)
    level, msg, values = mon.status(10.2)
    assert level == WARN and "cmd (empty)" in msg  # the last problem is shown
    assert values["cmd rejected"] == "3" and values["cmd received"] == "1"
    assert mon.stale(10.2) == ["ref"]
    level, msg, _ = mon.status(11.0)
    assert level == ERROR and "stale input: cmd" in msg
    mon2 = InputMonitor()
    mon2.add("x", timeout=1.0)
    mon2.accept("x", [0.0], now=0.0)
    assert mon2.status(0.5)[0] == OK


def test_split_ros_args():
    user, ros = split_ros_args(["--plant", "axis", "--ros-args", "-p", "kp:=3.0", "--params-file",
                                "f.yaml", "--", "--extra"])
    assert user == ["--plant", "axis", "--extra"]
    assert ros == ["--ros-args", "-p", "kp:=3.0", "--params-file", "f.yaml", "--"]


@pytest.mark.parametrize("package", ["cable_sim_node", "payload_estimator", "pd_feedforward"])
def test_node_main_help_and_missing_plant(package):
    out = subprocess.run([sys.executable, "-m", f"{package}.main", "--help"], capture_output=True,
                         text=True, timeout=60)
    assert out.returncode == 0 and "--plant" in out.stdout
    out = subprocess.run([sys.executable, "-m", f"{package}.main", "--plant", "axis", "--help"],
                         capture_output=True, text=True, timeout=60)
    assert out.returncode == 0
    out = subprocess.run([sys.executable, "-m", f"{package}.main", "--plant", "tower"],
                         capture_output=True, text=True, timeout=60)
    assert out.returncode == 2 and "tower" in out.stderr


# ----------------------------------------------------------------------------- conversions
def test_conversions_serialised_by_rclpy_decode_with_cablelab_codec():
    """rclpy's C serialiser (the rmw's CDR) and cablelab's vectorised decoder agree on every
    contract type: second implementation as oracle for both conversions and codec."""
    from rclpy.serialization import serialize_message

    from cablelab import cdr
    from cablelab.ros import convert

    rng = np.random.default_rng(5)
    p, q = rng.normal(size=3), rng.normal(size=4)
    cases = [
        (convert.joint_state_msg(12.345, ["w1", "w22"], [1.0, 2.0], None, [3.0, 4.0], frame_id="x"),
         "sensor_msgs/msg/JointState", {"position": [[1.0, 2.0]], "effort": [[3.0, 4.0]]}),
        (convert.pose_msg(1.5, p, q), "geometry_msgs/msg/PoseStamped",
         {"pose.position.z": [[p[2]]], "pose.orientation.w": [[q[3]]]}),
        (convert.inertia_msg(2.0, 366.0, p), "geometry_msgs/msg/InertiaStamped",
         {"inertia.m": [[366.0]], "inertia.com.y": [[p[1]]]}),
        (convert.float_array_msg([1.0, -2.0, 3.5]), "std_msgs/msg/Float64MultiArray",
         {"data": [[1.0, -2.0, 3.5]]}),
        (convert.joint_trajectory_msg(3.0, ["slew", "luff", "hoist"], p, None, -p),
         "trajectory_msgs/msg/JointTrajectory",
         {"points[0].positions": [p], "points[0].accelerations": [-p]}),
        (convert.multidof_msg(4.0, p, q, linear_velocity=p * 2),
         "trajectory_msgs/msg/MultiDOFJointTrajectory",
         {"points[0].transforms[0].rotation.x": [[q[0]]], "points[0].velocities[0].linear.y": [[2 * p[1]]],
          "points[0].velocities[0].angular.z": [[0.0]]}),
        (convert.clock_msg(7.25), "rosgraph_msgs/msg/Clock", {"clock.sec": [[7]], "clock.nanosec": [[250000000]]}),
    ]
    for msg, msgtype, expect in cases:
        raw = serialize_message(msg)
        (group,) = cdr.decode(msgtype, [raw, raw])
        for path, value in expect.items():
            np.testing.assert_allclose(group.get(path)[0:1], np.asarray(value, float), err_msg=f"{msgtype} {path}")
        layout = cdr.walk(msgtype, raw)
        # rosbags agrees on the same bytes (without rmw's trailing padding, which it refuses)
        ref = cdr.typestore().deserialize_cdr(raw[:layout.end], msgtype)
        assert type(ref).__name__.endswith(msgtype.split("/")[-1])
        if msgtype.endswith("JointState"):
            np.testing.assert_array_equal(ref.effort, [3.0, 4.0])
            assert list(ref.name) == ["w1", "w22"] and ref.header.frame_id == "x"
    # messages differing only in rmw's uninitialised trailing bytes still share one layout
    raw = bytearray(serialize_message(cases[0][0]))
    other = bytearray(raw)
    other[-1] ^= 0xFF
    assert len(cdr.decode("sensor_msgs/msg/JointState", [bytes(raw), bytes(other)])) == 1
    t, names, pos, vel, eff = convert.joint_state_arrays(cases[0][0])
    assert t == pytest.approx(12.345) and names == ["w1", "w22"] and vel is None
    md = convert.multidof_arrays(cases[5][0])
    np.testing.assert_allclose(md["linear_velocity"], 2 * p)
    assert md["linear_acceleration"] is None


# ----------------------------------------------------------------------------- adapters with bad input


def test_sim_node_survives_bad_commands(ros_context):
    from std_msgs.msg import Float64MultiArray

    from cablelab.plants.axis.nodes.sim import AxisSimNode

    node = AxisSimNode()
    try:
        good = Float64MultiArray(data=[4.0])
        node.on_command(good)
        assert node.u == 4.0
        for bad in ([float("nan")], [1.0, 2.0], []):
            node.on_command(Float64MultiArray(data=bad))
            assert node.u == 4.0
        node.tick()  # fresh command: applied
        assert node.sim.t > 0 and node.u == 4.0
        level, msg, values = node.inputs.status(__import__("time").monotonic())
        assert level == WARN and values["effort_command rejected"] == "3"
        node.inputs.inputs["effort_command"].last_time -= 10.0  # make it stale
        node.tick()
        assert node.u == 0.0  # stale command: drive off
    finally:
        node.destroy_node()


def test_controller_and_estimator_ignore_bad_states(ros_context):
    from sensor_msgs.msg import JointState

    from cablelab.ros import convert
    from cablelab.plants.axis.nodes.estimator import AxisEstimator
    from cablelab.plants.axis.nodes.controller import AxisController

    ctl, est = AxisController(), AxisEstimator()
    sent = []
    ctl.pub_cmd.publish = sent.append
    try:
        ctl.on_state(convert.joint_state_msg(1.0, ["joint"], [0.0], [0.0], [0.0]))
        assert not sent  # no reference yet: no command
        ctl.reference.on_message(convert.joint_trajectory_msg(1.0, ["joint"], [0.1], [0.0], [0.0]))
        ctl.on_state(convert.joint_state_msg(1.0, ["joint"], [0.0], [0.0], [0.0]))
        assert len(sent) == 1 and sent[0].data[0] == pytest.approx(ctl.kp * 0.1)
        ctl.on_state(convert.joint_state_msg(1.0, ["joint"], [float("nan")], [0.0], [0.0]))
        ctl.on_state(JointState())
        assert len(sent) == 1 and ctl.inputs.inputs["joint_states"].rejected == 2
        for m in (JointState(), convert.joint_state_msg(1.0, ["joint"], [0.0], [0.0], None)):
            est.on_state(m)
        assert est.inputs.inputs["joint_states"].rejected == 2 and est.est.rls.n == 0
    finally:
        ctl.destroy_node()
        est.destroy_node()


def test_run_node_applies_ros_parameters_and_yaml_files(tmp_path, domain_id, monkeypatch):
    """--ros-args -p and --params-file reach the node through the runner (rclpy's own parsing)."""
    from cablelab.ros.runner import run_node

    monkeypatch.setenv("ROS_DOMAIN_ID", str(domain_id))
    params = tmp_path / "params.yaml"
    params.write_text("/**:\n  ros__parameters:\n    inertia: 3.5\n    rate: 100.0\n")
    seen = {}

    def factory():
        from cablelab.plants.axis.nodes.sim import AxisSimNode

        node = AxisSimNode()
        seen.update(truth=node.sim.truth, rate=node.rate)
        node.done = True  # finish right away
        return node

    argv = ["--ros-args", "--params-file", str(params), "-p", "viscous:=7.0"]
    assert run_node(factory, argv, "cable_sim_node") == 0
    assert seen["truth"].inertia == 3.5 and seen["truth"].viscous == 7.0 and seen["rate"] == 100.0

    def broken():
        raise CablelabError("description: bad thing")

    assert run_node(broken, [], "cable_sim_node") == 2


def test_clock_publisher_is_monotonic_and_throttled(ros_context):
    from rclpy.node import Node

    from cablelab.ros.clock import ClockPublisher

    node = Node("clock_test")
    try:
        clock = ClockPublisher(node, period=0.01)
        sent = []
        clock.pub.publish = sent.append
        for t in (0.0, 0.004, 0.01, 0.009, 0.02, 0.031):
            clock.publish(t)
        assert [m.clock.sec + m.clock.nanosec * 1e-9 for m in sent] == pytest.approx([0.0, 0.01, 0.02, 0.031])
    finally:
        node.destroy_node()


# ----------------------------------------------------------------------------- launcher hygiene
def _alive(pid: int) -> bool:
    """True while ``pid`` runs (a zombie waiting for its new parent to reap it counts as dead)."""
    try:
        with open(f"/proc/{pid}/status") as fh:
            return not any(line.startswith("State:") and "Z" in line.split()[1] for line in fh)
    except OSError:
        return False


@pytest.mark.skipif(not sys.platform.startswith("linux"), reason="PR_SET_PDEATHSIG is Linux only")
def test_launched_nodes_die_with_a_killed_launcher(tmp_path):
    """A test run or demo killed with SIGKILL (no cleanup runs) leaves no orphan node: the
    children of a Launcher get SIGTERM from the kernel when it dies."""
    import signal
    import time

    script = ("import sys, time\nfrom cablelab.ros.launch import Launcher\n"
              f"la = Launcher(domain_id=1, log_dir={str(tmp_path)!r})\n"
              "p = la.start('child', [sys.executable, '-c', 'import time; time.sleep(300)'])\n"
              "print(p.popen.pid, flush=True)\ntime.sleep(300)\n")
    parent = subprocess.Popen([sys.executable, "-c", script], stdout=subprocess.PIPE, text=True)
    try:
        child = int(parent.stdout.readline())
        assert _alive(child)
        parent.send_signal(signal.SIGKILL)
        parent.wait(30)
        deadline = time.monotonic() + 60
        while _alive(child) and time.monotonic() < deadline:
            time.sleep(0.05)
        assert not _alive(child), f"orphan node {child} survived its launcher"
    finally:
        parent.kill()


def test_domain_ids_are_exclusive_across_processes():
    """Ids reserved by one process are never handed out to another one while held."""
    from cablelab.ros.launch import release_domain_id, reserve_domain_id

    mine = [reserve_domain_id(salt=s) for s in range(3)]
    try:
        code = ("from cablelab.ros.launch import reserve_domain_id\n"
                f"print(*[reserve_domain_id(salt=s) for s in range(3)])")
        out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, timeout=60)
        theirs = [int(x) for x in out.stdout.split()]
        assert len(theirs) == 3 and all(1 <= d <= 200 for d in theirs + mine)
        assert not set(theirs) & set(mine) and len(set(mine)) == 3
    finally:
        for d in mine:
            release_domain_id(d)
