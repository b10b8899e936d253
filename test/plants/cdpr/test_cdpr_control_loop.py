"""The CDPR control loop (``control_loop --plant cdpr``): its commands against the three-process
loop's controller node on one recorded state stream, the hardware seam, the deadline
accounting, and the loop over DDS surviving the estimator's death."""
from __future__ import annotations

import json
import time

import numpy as np
import pytest

from cablelab.errors import CablelabError


@pytest.fixture
def ros_context(domain_id):
    """rclpy for nodes built in the test's process; a control loop publishes in its own thread
    (``publisher:=loop``), so that the test sees every publish call."""
    import rclpy

    rclpy.init(args=["test", "--ros-args", "-p", "publisher:=loop"], domain_id=domain_id)
    yield
    rclpy.try_shutdown()


def _capture(out: list, cls):
    from rclpy.serialization import deserialize_message

    return lambda m: out.append(deserialize_message(m, cls) if isinstance(m, bytes) else m)


def test_loop_commands_equal_the_controller_node_on_a_recorded_stream(ros_context):
    """The loop node's commands (read -> ReferenceLaw -> write, reference terms prepared after
    each write, estimates taken between periods) equal what the ``pd_feedforward`` node answers to
    the same states, references and estimates as messages, to round-off: one law, two shells."""
    from std_msgs.msg import Float64MultiArray

    from cablelab.plants.cdpr.nodes.control_loop import CdprControlLoop
    from cablelab.plants.cdpr.nodes.controller import CdprController
    from cablelab.ros import convert

    loop_node = CdprControlLoop()
    ctl = CdprController()
    from_loop, from_node = [], []
    loop_node.cycle_pub.out.pub_cmd.publish = _capture(from_loop, Float64MultiArray)
    from sensor_msgs.msg import JointState
    from trajectory_msgs.msg import MultiDOFJointTrajectory
    js, tens, refs = [], [], []
    loop_node.cycle_pub.out.pub_js.publish = _capture(js, JointState)
    loop_node.cycle_pub.out.pub_ten.publish = _capture(tens, JointState)
    loop_node.cycle_pub.out.pub_ref.publish = _capture(refs, MultiDOFJointTrajectory)
    ctl.pub_cmd.publish = _capture(from_node, Float64MultiArray)
    ctl.polled = []                 # callbacks alone, no DDS
    loop_node.take_every = 10 ** 9  # estimates are fed by hand below, at the same points for both
    try:
        # record: the loop runs untimed on its simulated hardware (a payload the nominal mass
        # does not know), with live estimates at 100 Hz (and one NaN, one implausible)
        loop = loop_node.loop
        loop.start()
        states, estimates = [], {}
        rng = np.random.default_rng(3)
        for k in range(400):
            state, command = loop.cycle()
            states.append(state)
            if k % 10 == 5:
                m = {105: float("nan"), 205: 1e6}.get(k, 615.0 + rng.normal(0.0, 5.0))
                est = convert.inertia_msg(state.t, m, [0.05, -0.01, float("nan")])
                estimates[k] = est
                loop_node.on_estimate(est)
            loop_node._after_write(state, command)
        assert len(from_loop) == 400
        assert loop_node.estimates_rejected == 1 and loop_node.inputs.inputs["payload_estimate"].rejected == 1

        # replay the same stream to the controller node, as the three-process loop delivers it
        ctl.on_description(convert.string_msg(loop_node.description.to_yaml()))
        names = list(loop_node.hardware.joint_names)
        for k, st in enumerate(states):
            pos, vel, acc = loop_node.reference.at(st.t)
            ctl.on_reference(convert.multidof_msg(st.t, pos, [0, 0, 0, 1.0], vel, None, acc, None))
            ctl.on_state(convert.joint_state_msg(st.t, names, st.position, st.velocity, st.effort))
            if k in estimates:
                ctl.on_estimate(estimates[k])
        assert len(from_node) == 400
        a = np.array([m.data for m in from_loop])
        b = np.array([m.data for m in from_node])
        np.testing.assert_allclose(a, b, rtol=1e-12, atol=1e-9)
        # each command names the state it answers, in both
        assert [convert.command_stamp(m) for m in from_loop] == pytest.approx([s.t for s in states], abs=1e-9)
        # the live mass was used (not the nominal 366 kg): the feedforward follows the estimate
        assert loop_node.law.controller.mass == pytest.approx(ctl.controller.mass, rel=1e-12)
        assert abs(loop_node.law.controller.mass - 615.0) < 20.0
        # and the law was prepared ahead on the loop's side for most periods
        assert loop_node.law.prepared_used > 300
        assert np.isfinite(a).all() and (a > 0).all()
        # the loop's published state, tensions and reference are what it read and used (the
        # pre-serialised templates, read back by rclpy's deserialiser)
        assert len(js) == len(tens) == len(refs) == 400
        np.testing.assert_array_equal(np.array([m.position for m in js]), [s.position for s in states])
        np.testing.assert_array_equal(np.array([m.velocity for m in js]), [s.velocity for s in states])
        np.testing.assert_array_equal(np.array([m.effort for m in tens]), [s.extra["tension"] for s in states])
        assert [convert.from_stamp(m.header.stamp) for m in js] == pytest.approx([s.t for s in states], abs=1e-9)
        np.testing.assert_array_equal(
            [[m.points[0].transforms[0].translation.x, m.points[0].transforms[0].translation.z] for m in refs],
            [loop_node.reference.at(s.t)[0][[0, 2]] for s in states])
    finally:
        loop_node.loop.stop()
        loop_node.destroy_node()
        ctl.destroy_node()


def test_publisher_thread_publishes_every_sample_in_order(domain_id):
    """``publisher:=thread``: the samples queued after each write are all published by the
    thread, in the order of the periods, by the time the node shuts down."""
    import rclpy
    from sensor_msgs.msg import JointState
    from std_msgs.msg import Float64MultiArray

    from cablelab.plants.cdpr.nodes.control_loop import CdprControlLoop
    from cablelab.ros import convert

    rclpy.init(args=["test", "--ros-args", "-p", "publisher:=thread", "-p", "publish_batch:=0.002",
                     "-p", "rate:=500.0"], domain_id=domain_id)
    try:
        node = CdprControlLoop()
        js, cmds = [], []
        node.cycle_pub.out.pub_js.publish = _capture(js, JointState)
        node.cycle_pub.out.pub_cmd.publish = _capture(cmds, Float64MultiArray)
        try:
            node.loop.start()
            states = []
            for _ in range(300):
                state, command = node.loop.cycle()
                states.append(state)
                node._after_write(state, command)
            node.shutdown()
            assert [convert.from_stamp(m.header.stamp) for m in js] == pytest.approx([s.t for s in states], abs=1e-9)
            np.testing.assert_array_equal([m.position for m in js], [s.position for s in states])
            assert [convert.command_stamp(m) for m in cmds] == pytest.approx([s.t for s in states], abs=1e-9)
        finally:
            node.destroy_node()
    finally:
        rclpy.try_shutdown()


def test_hardware_seam():
    """The simulator satisfies the protocol; the stub stops with what a driver must implement;
    the loop counts a late wake-up like the bare timer does, and a write(None) brakes."""
    from cablelab.control_loop import ControlLoop
    from cablelab.hardware import DriverStub, HardwareInterface, load_hardware_class
    from cablelab.plants.cdpr.hardware import SimulatedCdpr
    from cablelab.plants.cdpr.sim import CdprTruth, default_description

    desc = default_description()
    hw = SimulatedCdpr(desc, CdprTruth(payload_mass=122.0, timestep=0.001), 500.0, [-1.0, -0.3, 0.6])
    assert isinstance(hw, HardwareInterface) and hw.nstep == 2
    stub = DriverStub(hw.joint_names, desc)
    assert isinstance(stub, HardwareInterface)
    for call in (stub.start, stub.read, lambda: stub.write(np.zeros(8))):
        with pytest.raises(CablelabError, match="not implemented.*hardware:=package.module:Class"):
            call()
    with pytest.raises(CablelabError, match="expected 'package.module:Class'"):
        load_hardware_class("nonsense")
    with pytest.raises(CablelabError, match="missing method"):
        load_hardware_class("cablelab.hardware:HardwareState")
    assert load_hardware_class("cablelab.hardware:DriverStub") is DriverStub

    class Hold:                     # a law that never has a command: the hardware brakes
        status = [(2, "no reference")]

        def update(self, state):
            return None

    # a fake clock: the 3rd period wakes 2.5 periods late, then everything is on time
    now = [0.0]
    wake = {2: 2.5}

    def sleep(t):
        k = int(round(t * 500.0))
        now[0] = max(now[0], t) + wake.pop(k, 0.0) / 500.0

    behind = []
    loop = ControlLoop(hw, Hold(), 500.0, warmup=0.0, clock=lambda: now[0], sleep=sleep,
                       after_write=lambda state, command: behind.append(loop.behind()))
    loop.start()
    p0 = hw.sim.truth_pose()[0].copy()
    loop.run_until(0.1)
    s = loop.stats
    # deadlines 0..49; period 2 woke 2.5 periods late: it and period 3 (run at once after it,
    # 1.5 periods behind) are late, period 4 (0.5 behind) is not
    assert s.cycles == 50 and s.late == 2 and s.dropped == 0 and s.missed_cycles == 2
    # after the writes of periods 2 and 3 the next deadline had passed (catching up), never else
    assert [k for k, b in enumerate(behind) if b] == [2, 3]
    assert hw.braked == 50 and np.linalg.norm(hw.sim.truth_pose()[0] - p0) < 0.02
    assert hw.sim.time == pytest.approx(0.1)    # one period of physics per write


def test_loop_survives_the_estimator_over_dds(launcher, diagnostics_seen):
    """control_loop + payload_estimator as processes: the loop takes the live estimate; when the
    estimator is killed it keeps running (its state stream goes on) and reports the stale
    estimate on /diagnostics as WARN within a bounded time. (Publishing through the publisher
    process, the default; the equality test above covers publishing in the loop's thread.)"""
    launcher.node("estimator", "payload_estimator", "cdpr", {"poll_period": 0.01})
    launcher.start("loop", [*_loop_argv(), "--ros-args", "-p", "rate:=250.0", "-p", "payload_mass:=249.0",
                            "-p", "estimate_timeout:=1.0"])
    probe, seen = diagnostics_seen

    def loop_alive():
        assert launcher.procs["loop"].alive(), launcher.procs["loop"].log()[-2000:]

    def spin_until(cond, timeout, what):
        end = time.monotonic() + timeout
        while time.monotonic() < end:
            loop_alive()
            probe.executor.spin_once(timeout_sec=0.05)
            if cond():
                return
        raise AssertionError(f"timeout after {timeout} s waiting for {what}; control_loop diagnostics: "
                             f"{seen.get('control_loop')}")

    def loop_values():
        return seen.get("control_loop", (None, "", {}, 0.0))

    # the live estimate reaches the loop's feedforward (not the nominal mass)
    spin_until(lambda: loop_values()[2].get("feedforward mass kg", "-") not in ("-", "366.0")
               and int(loop_values()[2].get("payload_estimate received", "0")) > 5, 120, "estimates taken by the loop")
    mass = float(loop_values()[2]["feedforward mass kg"])
    assert 500.0 < mass < 700.0, mass       # 366 kg platform + 249 kg payload
    cycles_before = int(loop_values()[2]["commands"])
    launcher.kill("estimator")
    killed = time.monotonic()
    spin_until(lambda: loop_values()[0] == 1 and "stale" in loop_values()[1] and loop_values()[3] > killed,
               60, "a WARN about the stale estimate")
    level, message, values, _ = loop_values()
    assert "payload_estimate" in message or "estimate stale" in message, message
    # the loop goes on commanding and publishing its state after the estimator died
    counts = probe.wait_for_topics({"/cdpr/joint_states": 50, "/cdpr/effort_commands": 50}, 60, loop_alive)
    assert min(counts.values()) >= 50
    spin_until(lambda: int(loop_values()[2]["commands"]) > cycles_before + 100, 60, "more commands")
    assert launcher.procs["loop"].alive()
    codes = launcher.stop_all()
    assert codes["loop"] == 0, launcher.procs["loop"].log()[-2000:]
    summary = [ln for ln in launcher.procs["loop"].log().splitlines() if ln.startswith('{"node": "control_loop"')]
    assert summary, launcher.procs["loop"].log()[-2000:]


def test_recorder_gets_every_sample_through_the_publisher_process(launcher, tmp_path):
    """The loop's samples go through the shared-memory ring to its publisher process (the
    default ``publisher:=process``): a recorder started before the loop records every period's
    joint state, tensions and command, once each and in the order of the periods, and the values
    are the simulated robot's (the commands pull on every cable; the stamps are the loop's)."""
    import sys

    from cablelab.bags import open_bag

    bag_dir = tmp_path / "run"
    launcher.start("recorder", [sys.executable, "-m", "cablelab.cli", "record", "--plant", "cdpr",
                                "-o", bag_dir, "--quiet"])
    launcher.wait_for_subscribers(["/cdpr/joint_states", "/cdpr/effort_commands"], timeout=120,
                                  node_name="cablelab_recorder")
    # 8 s: the publisher process is a new DDS participant that the recorder must discover before
    # its samples can reach it (on a busy machine that took longer than a 3 s run once)
    rate, duration = 500.0, 8.0
    loop = launcher.start("loop", [*_loop_argv(), "--ros-args", "-p", f"rate:={rate}", "-p", f"duration:={duration}",
                                   "-p", "warmup:=0.0"])
    assert loop.wait(600) == 0, loop.log()[-2000:]
    summary = json.loads([ln for ln in loop.log().splitlines() if ln.startswith('{"node": "control_loop"')][-1])
    n = summary["samples_written"]                  # stamps 0 .. duration (+ round-off), one per period
    assert n in (duration * rate + 1, duration * rate + 2), n
    assert summary["publisher"] == "process" and summary["commands"] == n
    assert summary["samples_published"] == n and summary["samples_lost"] == 0
    # every sample was published (above); what the recorder got: from its first sample (the
    # publisher waits for the subscribers it has discovered; on a very busy machine discovery may
    # take longer, which is DDS's matter, not the loop's) to the last, each period once, in order
    last = (n - 1) / rate
    deadline = time.monotonic() + 180
    while True:
        try:
            bag = open_bag(bag_dir, recover=True)
            done = all(bag.has(t) and bag.counts[t] and abs(_last_stamp(bag, t) - last) < 1e-9
                       for t in ("/cdpr/joint_states", "/cdpr/cable_tensions", "/cdpr/effort_commands"))
        except CablelabError:
            done = False
        if done or time.monotonic() > deadline:
            break
        time.sleep(0.5)
    codes = launcher.stop_all()
    assert codes["recorder"] == 0, codes
    bag = open_bag(bag_dir)
    stamps = {t: bag.joint_state(t).t for t in ("/cdpr/joint_states", "/cdpr/cable_tensions")}
    from cablelab.ros.convert import label_stamp
    stamps["/cdpr/effort_commands"] = np.array([label_stamp(m.layout.dim[0].label)
                                                for m in bag.messages("/cdpr/effort_commands")])
    for topic, t in stamps.items():
        k0 = int(round(t[0] * rate))
        assert k0 <= 0.5 * rate, (topic, t[0])                  # recorded from early on
        np.testing.assert_allclose(t, np.arange(k0, n) / rate, atol=1e-9, err_msg=topic)  # none lost, in order
    assert np.isfinite(bag.joint_state("/cdpr/cable_tensions").effort).all()
    cmd = bag.float_array("/cdpr/effort_commands")
    assert (cmd.data > 0).all()                                  # every command pulls on every cable


def _last_stamp(bag, topic):
    if topic == "/cdpr/effort_commands":
        from cablelab.ros.convert import label_stamp

        return label_stamp(bag.messages(topic)[-1].layout.dim[0].label)
    return float(bag.joint_state(topic).t[-1])


def _loop_argv():
    import sys

    return [sys.executable, "-m", "pd_feedforward.control_loop", "--plant", "cdpr"]


@pytest.mark.parametrize("stamp", [0.0, 9.999, 12.345678901, 1234.5])
def test_command_template_equals_rclpy(ros_context, stamp):
    """A pre-serialised command is byte for byte what rclpy serialises for convert.command_msg."""
    from rclpy.serialization import serialize_message

    from cablelab.ros import convert
    from cablelab.ros.rawmsg import CommandTemplate

    tpl = CommandTemplate("winch")
    for cmd in (np.arange(8.0) * 1.5, np.linspace(-3.0, 7.0, 8), np.ones(4)):
        assert tpl.data(cmd, stamp) == serialize_message(convert.command_msg(cmd, stamp=stamp, label="winch"))


class ScriptedDriver:
    """A user's driver as the loop sees it (built from ``hardware:=module:Class``): it reports
    the motor state of a platform hanging at the start point and keeps what it is sent."""

    def __init__(self, joint_names, description):
        from cablelab.hardware import HardwareState
        from cablelab.plants.cdpr.control import motor_angles
        from cablelab.plants.cdpr.geometry import cable_geometry
        from cablelab.plants.cdpr.trajectory import pick_and_place

        self.joint_names = tuple(joint_names)
        c = description.cdpr
        start = pick_and_place(np.array([0.0])).position[0]
        g = cable_geometry(c.exit_points, c.anchor_points, start[None], None, c.pulley_radius, c.swivel_axes)
        self.q = motor_angles(g.lengths, c.drum_radius, c.gear_ratio)[0]
        self.State, self.t, self.sent, self.events = HardwareState, 0.0, [], []

    def start(self):
        self.events.append("start")

    def read(self):
        self.t += 0.002
        n = len(self.joint_names)
        return self.State(self.t, self.q.copy(), np.zeros(n), np.zeros(n), {})

    def write(self, command):
        self.sent.append(None if command is None else np.array(command))

    def stop(self):
        self.events.append("stop")


def test_a_driver_plugs_in_by_parameter(domain_id):
    """``hardware:=module:Class`` replaces the simulator without touching the loop: the loop
    starts the driver, writes it the law's command for the state it read (the IGM of the start
    point, so only gravity feedforward and friction compensation), stops it at the end."""
    import rclpy

    from cablelab.plants.cdpr.nodes.control_loop import CdprControlLoop

    rclpy.init(args=["test", "--ros-args", "-p", f"hardware:={__name__}:ScriptedDriver", "-p", "rate:=500.0"],
               domain_id=domain_id)
    try:
        node = CdprControlLoop()
        try:
            drv = node.hardware
            assert isinstance(drv, ScriptedDriver) and not node.simulated
            node.loop.start()
            for _ in range(20):
                state, command = node.loop.cycle()
                node._after_write(state, command)
            node.shutdown()
            assert drv.events == ["start", "stop"] and len(drv.sent) == 20
            # the law of the pd_feedforward node for that state, independently: LiveController
            from cablelab.plants.cdpr.live import ControllerConfig, LiveController
            from cablelab.plants.cdpr.control import PdffConfig
            c = node.description.cdpr
            ctl = LiveController(c, node.description.gravity,
                                 ControllerConfig(nominal_mass=c.platform_mass or 366.0,
                                                  gains=PdffConfig(coulomb=0.3, viscous=0.002)))
            pos, vel, acc = node.reference.at(0.04)
            want = ctl.update(0.04, drv.q, np.zeros(len(drv.q)), pos, None, vel, acc)
            np.testing.assert_allclose(drv.sent[-1], want, rtol=1e-12)
            # the platform is held against gravity: every cable pulls (reels in)
            assert (drv.sent[-1] > 0).all()
        finally:
            node.destroy_node()
    finally:
        rclpy.try_shutdown()


def test_loop_survives_any_estimate(ros_context):
    """Whatever arrives on /cdpr/payload_estimate (NaN, inf, negative or absurd masses, NaN or
    absurd CoM, any stamp), the loop's next commands are finite and pull on every cable: a bad
    estimate is rejected and counted, never fed to the feedforward."""
    from hypothesis import HealthCheck, given, settings, strategies as st

    from cablelab.plants.cdpr.nodes.control_loop import CdprControlLoop
    from cablelab.ros import convert

    node = CdprControlLoop()
    out = node.cycle_pub.out
    out.pub_cmd.publish = out.pub_js.publish = out.pub_ten.publish = out.pub_ref.publish = lambda m: None
    node.loop.start()
    anchors = node.description.cdpr.anchor_points[:, :2]
    num = st.one_of(st.floats(allow_nan=True, allow_infinity=True), st.sampled_from([0.0, -615.0, 615.0, 1e300]))

    @settings(max_examples=40, deadline=None, suppress_health_check=list(HealthCheck), derandomize=True)
    @given(m=st.one_of(num, st.just(615.0)), x=num, y=num, dt=st.floats(-1e3, 1e3))
    def check(m, x, y, dt):
        state, _ = node.loop.cycle()
        node.on_estimate(convert.inertia_msg(max(0.0, state.t + dt), m, [x, y, float("nan")]))
        node._after_write(state, None)
        _, command = node.loop.cycle()
        assert command is not None and np.isfinite(command).all() and (command > 0).all()
        mass = node.law.controller.mass
        assert mass is None or (np.isfinite(mass) and 0.5 * 366.0 <= mass <= 3.0 * 366.0)
        # the CoM stays on the platform (within twice its farthest anchor): the feedforward
        # tensions stay those of a load the platform can carry, not 1e300 N clipped by max_torque
        assert np.abs(node.law.controller.com).max() <= 2.0 * np.abs(anchors).max()
        ff = node.law.terms(state.t).tensions_ff
        assert np.isfinite(ff).all() and ff.max() < 1e5

    try:
        check()
    finally:
        node.loop.stop()
        node.destroy_node()
