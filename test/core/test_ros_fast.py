"""The 1 kHz node helpers: pre-serialised message templates (oracle: rclpy's own serialiser and
deserialiser) and FastExecutor (every message delivered once, in order, timers and services)."""
from __future__ import annotations

import time

import numpy as np
import pytest


def test_templates_equal_rclpy_serialisation():
    from geometry_msgs.msg import InertiaStamped, PoseStamped
    from rclpy.serialization import deserialize_message, serialize_message
    from sensor_msgs.msg import JointState
    from std_msgs.msg import Float64MultiArray, MultiArrayDimension
    from trajectory_msgs.msg import MultiDOFJointTrajectory

    from cablelab import cdr
    from cablelab.ros import convert
    from cablelab.ros.rawmsg import RawTemplate

    rng = np.random.default_rng(1)
    names = [f"winch_{i}" for i in range(1, 9)]
    z = np.zeros(8)
    tpl = RawTemplate(convert.joint_state_msg(0.0, names, z, z, z))
    for t in (0.0, 1.001, 12345.678901234):
        q, qd, e = rng.normal(size=(3, 8))
        tpl.stamp(t)
        tpl["position"][:], tpl["velocity"][:], tpl["effort"][:] = q, qd, e
        # byte for byte what rclpy serialises for the same message object, except the alignment
        # padding, which rclpy's serialiser leaves uninitialised (whatever the memory held)
        want = bytes(serialize_message(convert.joint_state_msg(t, names, q, qd, e)))
        assert len(tpl.data()) == len(want)
        free = np.zeros(len(want), dtype=bool)
        lay = cdr.walk("sensor_msgs/msg/JointState", want)
        for off, n in lay.padding:
            free[off:off + n] = True
        free[lay.end:] = True
        got_b, want_b = np.frombuffer(tpl.data(), np.uint8), np.frombuffer(want, np.uint8)
        assert np.array_equal(got_b[~free], want_b[~free]) and lay.padding
        back = deserialize_message(tpl.data(), JointState)
        assert back.header.stamp == convert.to_stamp(t) and list(back.name) == names
        assert np.array_equal(back.position, q) and np.array_equal(back.effort, e)

    ref = RawTemplate(convert.multidof_msg(0.0, np.zeros(3), [0, 0, 0, 1.0], np.zeros(3), None, np.zeros(3), None))
    p, v, a = rng.normal(size=(3, 3))
    ref.vector("points[0].transforms[0].translation")[:] = p
    ref.vector("points[0].velocities[0].linear")[:] = v
    ref.vector("points[0].accelerations[0].linear")[:] = a
    ref.stamp(2.5)
    d = convert.multidof_arrays(deserialize_message(ref.data(), MultiDOFJointTrajectory))
    assert d["t"] == 2.5 and np.array_equal(d["position"], p)
    assert np.array_equal(d["linear_velocity"], v) and np.array_equal(d["linear_acceleration"], a)
    assert np.array_equal(d["quaternion"], [0, 0, 0, 1.0])

    pose = RawTemplate(convert.pose_msg(0.0, np.zeros(3), [0, 0, 0, 1.0]))
    pose.vector("pose.orientation", "xyzw")[:] = [0.1, 0.2, 0.3, 0.9]
    o = deserialize_message(pose.data(), PoseStamped).pose.orientation
    assert (o.x, o.y, o.z, o.w) == (0.1, 0.2, 0.3, 0.9)

    est = RawTemplate(convert.inertia_msg(0.0, 0.0, [0.0, 0.0, float("nan")]))
    est["inertia.m"][0] = 615.0
    est.vector("inertia.com")[:2] = [0.06, -0.01]
    back = deserialize_message(est.data(), InertiaStamped)
    assert back.inertia.m == 615.0 and back.inertia.com.x == 0.06 and np.isnan(back.inertia.com.z)

    msg = Float64MultiArray(data=[1.0] * 8)
    msg.layout.dim = [MultiArrayDimension(label="winch stamp=1.000000000", size=8, stride=8)]
    cmd = RawTemplate(msg)
    cmd.write_text(cmd.text_offset("winch stamp=1.000000000"), "winch stamp=7.123456789")
    assert deserialize_message(cmd.data(), Float64MultiArray).layout.dim[0].label == "winch stamp=7.123456789"
    with pytest.raises(KeyError, match="no numeric field"):
        RawTemplate(convert.joint_state_msg(0.0, names, z, None, z))["velocity"]   # empty sequence


def test_raw_inertia_equals_the_deserialised_message():
    """rawmsg.inertia_arrays of an InertiaStamped's bytes (the controller takes the estimates raw)
    equals convert.inertia_arrays of the message rclpy deserialises from them; bytes of another
    type raise ValueError."""
    from geometry_msgs.msg import InertiaStamped
    from rclpy.serialization import deserialize_message, serialize_message

    from cablelab.ros import convert, rawmsg

    reader = rawmsg.RawReader(InertiaStamped)
    rng = np.random.default_rng(5)
    for k in range(20):
        msg = convert.inertia_msg(float(rng.uniform(0, 1e4)), float(rng.uniform(-1e3, 1e3)),
                                  [rng.normal(), rng.normal(), np.nan if k % 3 else rng.normal()])
        msg.header.frame_id = "platform" if k < 10 else "a_longer_frame_name"     # (a new layout)
        raw = serialize_message(msg)
        t, m, com = rawmsg.inertia_arrays(raw, reader)
        t0, m0, com0 = convert.inertia_arrays(deserialize_message(raw, InertiaStamped))
        assert (t, m) == (t0, m0)
        np.testing.assert_array_equal(com, com0)
    assert reader.parsed == 2
    with pytest.raises(ValueError):
        rawmsg.inertia_arrays(b"\x00\x01\x00\x00" + bytes(8), rawmsg.RawReader(InertiaStamped))


def test_fast_executor_delivers_every_message_in_order(ros_context):
    from rclpy.node import Node
    from sensor_msgs.msg import JointState
    from std_msgs.msg import Float64MultiArray

    from cablelab.ros import convert
    from cablelab.ros.fastspin import FastExecutor, supports
    from cablelab.ros.qos import stream_qos
    from cablelab.ros.rawmsg import RawTemplate

    node = Node("fast_test", start_parameter_services=False)
    got_js, got_cmd, ticks = [], [], []
    node.create_subscription(JointState, "/t/js", lambda m: got_js.append(m.header.stamp.nanosec),
                             stream_qos(1000))
    node.create_subscription(Float64MultiArray, "/t/cmd", lambda m: got_cmd.append(m.data[0]), stream_qos(1000))
    node.create_timer(0.01, lambda: ticks.append(time.monotonic()))
    pub_js = node.create_publisher(JointState, "/t/js", stream_qos(1000))
    pub_cmd = node.create_publisher(Float64MultiArray, "/t/cmd", stream_qos(1000))
    assert supports(node)
    ex = FastExecutor()
    ex.add_node(node)
    deadline = time.monotonic() + 30
    while not (pub_js.get_subscription_count() and pub_cmd.get_subscription_count()):
        assert time.monotonic() < deadline, "no intra-process match"
        ex.spin_once(0.05)
    tpl = RawTemplate(convert.joint_state_msg(0.0, ["a"], [0.0], [0.0], [0.0]))
    n = 500
    for k in range(n):            # a backlog on two topics: bytes and message objects
        tpl.stamp(k * 1e-3)
        pub_js.publish(tpl.data())
        pub_cmd.publish(Float64MultiArray(data=[float(k)]))
    deadline = time.monotonic() + 60
    while (len(got_js) < n or len(got_cmd) < n or len(ticks) < 3) and time.monotonic() < deadline:
        ex.spin_once(0.05)
    assert got_js == [k * 1_000_000 for k in range(n)]        # each once, in order
    assert got_cmd == [float(k) for k in range(n)]
    assert len(ticks) >= 3 and ex.taken >= 2 * n
    # a subscription created later is picked up
    late = []
    node.create_subscription(Float64MultiArray, "/t/cmd", lambda m: late.append(m.data[0]), stream_qos(10))
    deadline = time.monotonic() + 30
    while not late and time.monotonic() < deadline:
        pub_cmd.publish(Float64MultiArray(data=[-1.0]))
        ex.spin_once(0.05)
    assert late and late[0] == -1.0
    node.destroy_node()


def test_a_timer_destroyed_by_an_earlier_callback_of_the_same_wake_up_is_skipped(ros_context):
    """Two timers due in one wake-up, the first destroying the second and creating a new one (as
    pd_feedforward does to change its period): the wake-up ends without error, the destroyed
    timer's callback does not run and the new timer runs on the next wake-ups."""
    from rclpy.node import Node

    from cablelab.ros.fastspin import FastExecutor

    node = Node("timer_swap_test", start_parameter_services=False)
    ran = []
    timers = {}

    def first():
        ran.append("first")
        if "second" in timers:
            node.destroy_timer(timers.pop("second"))
            timers["new"] = node.create_timer(0.001, lambda: ran.append("new"))

    timers["first"] = node.create_timer(0.001, first)
    timers["second"] = node.create_timer(0.001, lambda: ran.append("second"))
    ex = FastExecutor()
    ex.add_node(node)
    time.sleep(0.01)                    # both due
    ex.spin_once(1.0)
    assert ran == ["first"]
    deadline = time.monotonic() + 5
    while "new" not in ran and time.monotonic() < deadline:
        ex.spin_once(0.1)
    assert "new" in ran and "second" not in ran
    node.destroy_node()


def test_polled_subscription_wakes_nobody_and_drains_in_step(ros_context):
    """A polled subscription stays out of the wait set (its samples do not end a wait) and
    :func:`drain` takes every queued sample, two streams interleaved in publishing order."""
    from rclpy.node import Node
    from std_msgs.msg import Float64MultiArray

    from cablelab.ros.fastspin import FastExecutor, drain, poll, take_newest
    from cablelab.ros.qos import stream_qos

    node = Node("poll_test", start_parameter_services=False)
    got = []
    subs = [node.create_subscription(Float64MultiArray, f"/p/{k}", lambda m, k=k: got.append((k, m.data[0])),
                                     stream_qos(100)) for k in ("a", "b")]
    for s in subs:
        poll(node, s)
    pubs = {k: node.create_publisher(Float64MultiArray, f"/p/{k}", stream_qos(100)) for k in ("a", "b")}
    ex = FastExecutor()
    ex.add_node(node)
    deadline = time.monotonic() + 30
    while not all(p.get_subscription_count() for p in pubs.values()):
        assert time.monotonic() < deadline, "no intra-process match"
        time.sleep(0.05)
    for i in range(20):
        for k in ("a", "b"):
            pubs[k].publish(Float64MultiArray(data=[float(i)]))
    time.sleep(0.2)                      # delivered into the queues by now
    t0 = time.monotonic()
    ex.spin_once(0.3)                    # nothing in the wait set is ready: the full timeout
    assert time.monotonic() - t0 > 0.25 and not got
    assert drain(*subs) == 40
    assert got == [(k, float(i)) for i in range(20) for k in ("a", "b")]
    assert drain(*subs) == 0
    # take_newest on a keep-last-1 queue: one take gets the newest sample, then nothing
    last = []
    one = node.create_subscription(Float64MultiArray, "/p/a", lambda m: last.append(m.data[0]), stream_qos(1))
    poll(node, one)
    while pubs["a"].get_subscription_count() < 2:
        assert time.monotonic() < deadline, "no intra-process match"
        time.sleep(0.05)
    for i in range(5):
        pubs["a"].publish(Float64MultiArray(data=[float(i)]))
    time.sleep(0.2)
    assert take_newest(one) and last == [4.0]
    assert not take_newest(one) and last == [4.0]
    node.destroy_node()


def test_stamped_buffer_looks_up_the_newest_sample_not_newer_than_t():
    from cablelab.stamped import StampedBuffer

    b = StampedBuffer(size=4)
    assert b.at(1.0) is None and not b
    for k in range(6):                   # stamps 0.000 .. 0.005, the last four kept
        b.push(k * 1e-3, k)
    assert b.newest == pytest.approx(5e-3)
    assert b.at(3e-3) == (pytest.approx(3e-3), 3)          # exact stamp (float rounding tolerated)
    assert b.at(3.5e-3)[1] == 3 and b.at(9.0)[1] == 5        # the newest not newer than t
    assert b.at(0.0)[1] == 2                                 # older than kept: the oldest kept
    assert b.after(3e-3)[1] == 4 and b.after(3.5e-3)[1] == 4   # the next one after t
    assert b.after(5e-3) is None and b.after(-1.0)[1] == 2
    b.push(1e-3, 99)                                         # went back in time: restarted
    assert b.newest == pytest.approx(1e-3) and b.at(9.0)[1] == 99


def test_scheduling_helpers_apply_to_every_thread():
    """set_idle_class and set_latency_slice (no privilege) act on every thread of the process
    they run in, as the kernel reports it in /proc (policy field of stat; se.slice of sched):
    run in a child process so that this one keeps its scheduling."""
    import subprocess
    import sys

    code = r"""
import os, threading, time
from cablelab.ros.fastspin import set_idle_class, set_latency_slice
ev = threading.Event()
t = threading.Thread(target=ev.wait); t.start()           # a second thread, like DDS's
print(set_latency_slice(0.0002))
slices = []
for tid in os.listdir("/proc/self/task"):
    for line in open(f"/proc/self/task/{tid}/sched"):
        if line.startswith("se.slice"):
            slices.append(int(line.split(":")[1]))
print("SLICES", slices)
print(set_idle_class())
print("POLICY", [int(open(f"/proc/self/task/{tid}/stat").read().rsplit(")", 1)[1].split()[38])
                 for tid in os.listdir("/proc/self/task")])
ev.set(); t.join()
"""
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, timeout=60).stdout
    lines = dict(line.split(" ", 1) for line in out.splitlines() if line.startswith(("SLICES", "POLICY")))
    assert "threads" in out, out
    assert set(eval(lines["POLICY"])) == {5}          # SCHED_IDLE on every thread
    if "time slice 0.2 ms on" in out:                 # kernel >= 6.12 (EEVDF custom slices)
        assert set(eval(lines["SLICES"])) == {200000}
    else:
        assert "not available" in out, out


def test_yield_to_compiled_lowers_only_the_calling_thread():
    """A node's Python thread steps back for its compiled thread: the caller's nice value rises,
    the other threads of the process (here the test's main thread) keep theirs."""
    import os
    import threading

    from cablelab.ros.fastspin import yield_to_compiled

    main_nice = os.getpriority(os.PRIO_PROCESS, threading.get_native_id())
    seen = {}

    def worker():
        seen["msg"] = yield_to_compiled(7)
        seen["nice"] = os.getpriority(os.PRIO_PROCESS, threading.get_native_id())

    t = threading.Thread(target=worker)
    t.start()
    t.join()
    assert seen["nice"] == max(7, main_nice) and str(seen["nice"]) in seen["msg"]
    assert os.getpriority(os.PRIO_PROCESS, threading.get_native_id()) == main_nice


def test_yield_to_compiled_idle_puts_only_the_calling_thread_in_sched_idle():
    """``idle=True`` (node parameter ``python_idle``): the caller goes to SCHED_IDLE, the process's
    other threads stay in their class."""
    import os
    import threading

    from cablelab.ros.fastspin import yield_to_compiled

    main_policy = os.sched_getscheduler(threading.get_native_id())
    seen = {}

    def worker():
        seen["msg"] = yield_to_compiled(idle=True)
        seen["policy"] = os.sched_getscheduler(threading.get_native_id())

    t = threading.Thread(target=worker)
    t.start()
    t.join()
    assert seen["policy"] == os.SCHED_IDLE and "SCHED_IDLE" in seen["msg"]
    assert main_policy != os.SCHED_IDLE and os.sched_getscheduler(threading.get_native_id()) == main_policy
