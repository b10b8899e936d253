"""The simulator node's compiled per-period path (csrc/sim_path.c) against the Python
SimStepper, its oracle: the same command stream (commands answering each state, gaps on the
brakes, a payload put on while running) gives the same trajectory and the same counts."""
from types import SimpleNamespace

import numpy as np
import pytest

from cablelab.plants.cdpr.nodes.parameters import SIM
from cablelab.plants.cdpr.sim import default_description
from cablelab.plants.cdpr.sim_path import CompiledSimPath, library
from cablelab.plants.cdpr.stepping import SimStepper
from cablelab.ros.params import check_all

lib = library()
pytestmark = pytest.mark.skipif(lib is None, reason="no compiled sim_path (CABLELAB_NATIVE=0 or no compiler)")


def steppers(**params):
    v = SimpleNamespace(**check_all(SIM, {"rate": 1000.0, **params}))
    desc = default_description()
    return SimStepper.from_parameters(desc, v), SimStepper.from_parameters(desc, v)


def command_stream(py: SimStepper, steps: int, seed: int = 1) -> np.ndarray:
    """Torques about the hanging platform's holding torques, with two gaps (NaN: no command, the
    brakes hold), one before the first command."""
    c = py.sim.desc.cdpr
    hold = (c.drum_radius / c.gear_ratio) * py.sim.truth_state()["tension"]
    rng = np.random.default_rng(seed)
    u = hold + np.cumsum(rng.normal(0.0, 0.05, (steps, py.sim.n)), axis=0)
    u[:5] = np.nan
    u[120:160] = np.nan
    u[400:403] = np.nan
    return u


def run_python(py: SimStepper, commands: np.ndarray) -> np.ndarray:
    """The Python law: row i answers the last state (or none came); qpos after each step."""
    out = []
    for row in commands:
        fresh = not np.isnan(row[0])
        if fresh:
            py.command(row, py.sim.time)
        py.step(0.0, fresh=fresh)
        out.append(np.concatenate([[py.sim.time], py.sim.data.qpos, py.sim.data.qvel]))
    return np.array(out)


@pytest.mark.parametrize("params", [{}, {"mass_change": 122.0, "mass_change_time": 0.3}])
def test_compiled_steps_equal_python_steps_for_the_same_commands(params):
    py, cs = steppers(**params)
    path = CompiledSimPath(lib, cs, command_timeout=0.2)
    try:
        commands = command_stream(py, 600)
        expected = run_python(py, commands)
        path.run_commands(commands)
        rows = path.drain()
        m = path.model
        got = np.hstack([rows[:, :1], rows[:, 4:4 + m.nq + m.nv]])
        assert len(rows) == len(commands)
        assert np.array_equal(got[:, 0], expected[:, 0])
        # identical arithmetic (same mj_step, same brake law, no fused multiply-adds): to round-off
        np.testing.assert_allclose(got, expected, rtol=0, atol=1e-12)
        assert np.ptp(expected[:, 1 + 7 * 0:4], axis=0).max() > 1e-4      # the platform moved
        c = path.update()
        assert (c["steps"], c["fallbacks"], c["fallbacks_running"]) == (py.k, py.fallbacks, py.fallbacks_running)
        assert c["slack"] == py.slack_steps and c["missed"] == py.missed_steps
        assert cs.command_age == py.command_age
        if params:
            assert c["mass_changed"] == 1 and py.mass_change == 0.0
            b = m.body("platform").id
            assert m.body_mass[b] == py.sim.model.body_mass[b] > 300.0
            # the drained sample at which it went on makes the mirror's truth follow
            for row in rows:
                *_, put_on = path.mirror(row)
                if put_on:
                    cs.put_on_mass(model=False)
            assert cs.sim.truth.platform_mass == py.sim.truth.platform_mass
        # the mirror (the stepper's own MjData) now reads the last sample: the measurements follow
        path.mirror(rows[-1])
        np.testing.assert_allclose(cs.sim.truth_state()["tension"], py.sim.truth_state()["tension"], atol=1e-9)
    finally:
        path.close()


def test_the_node_with_the_compiled_path_survives_bad_commands(ros_context):
    """The simulator node in real time runs the compiled path: NaN, wrong-length and empty
    commands over DDS are rejected and reported on its /diagnostics status (as the Python path
    reports them), the C thread keeps stepping on the brakes, a good command answering the last
    state is taken; the states it publishes arrive with their stamps on the grid; its publish and
    wake-up delays (/diagnostics) are counted from the first good command on."""
    import time

    import rclpy
    from rclpy.executors import SingleThreadedExecutor
    from sensor_msgs.msg import JointState
    from std_msgs.msg import Float64MultiArray

    from cablelab.plants.cdpr.nodes.sim import CdprSimNode
    from cablelab.ros import convert
    from cablelab.ros.qos import stream_qos

    sim = CdprSimNode()
    peer = rclpy.create_node("bad_controller")
    states = []
    pub = peer.create_publisher(Float64MultiArray, "/cdpr/effort_commands", stream_qos())
    peer.create_subscription(JointState, "/cdpr/joint_states", states.append, stream_qos(1000))
    ex = SingleThreadedExecutor()
    ex.add_node(sim)
    ex.add_node(peer)
    try:
        assert sim.path == "compiled" and sim.compiled is not None

        def spin_until(cond, timeout=60.0):
            end = time.monotonic() + timeout
            while not cond() and time.monotonic() < end:
                ex.spin_once(timeout_sec=0.01)
            return cond()

        assert spin_until(lambda: sim.compiled.started and pub.get_subscription_count() > 0 and len(states) > 5)
        nan = float("nan")
        sent = 0
        for bad in ([nan] * 8, [1.0] * 7, []):
            pub.publish(Float64MultiArray(data=bad))
            sent += 1
            # keep-last 1 on the C side: wait until each one was taken before the next
            assert spin_until(lambda: sim.compiled.update()["rejected"] >= sent, 30.0)
        level, msg, values = sim.status()
        assert values["effort_commands rejected"] == "3" and "rejected messages on effort_commands" in msg
        assert values["per-period path"] == "compiled"
        # publish and wake-up delays are counted only once commands come (start-up is not the loop)
        slow = "publishes over 0.2 ms (joint states/tensions/reference)"
        assert (values[slow], values["slowest publish ms"], values["latest wake-up ms"]) == ("0/0/0", "0.000", "0.000")
        k0 = sim.stepper.k
        assert spin_until(lambda: sim.stepper.k > k0 + 50)      # still stepping (on the brakes)
        assert sim.stepper.fallbacks == sim.stepper.k and sim.stepper.commands == 0
        # a good command answering the last state it published
        t = convert.from_stamp(states[-1].header.stamp)
        kb = sim.stepper.k          # (no step before this one publishes after the command)
        pub.publish(convert.command_msg(np.array(states[-1].effort), t, "winch"))
        assert spin_until(lambda: sim.compiled.update(sim.inputs)["commands"] == 1, 30.0)
        assert sim.inputs.inputs["effort_commands"].received == 1
        k1 = sim.stepper.k
        assert spin_until(lambda: sim.stepper.k > k1 + 20)
        values = sim.status()[2]
        # every wake-up comes after its deadline and every publish takes time: both maxima > 0
        assert float(values["latest wake-up ms"]) > 0 and float(values["slowest publish ms"]) > 0
        # three publishes per step at most (joint states, tensions, reference), counted from the command on
        assert sum(map(int, values[slow].split("/"))) <= 3 * (sim.stepper.k - kb + 1)
        stamps = np.array([convert.from_stamp(s.header.stamp) for s in states])
        np.testing.assert_allclose(stamps * 1000.0, np.round(stamps * 1000.0), atol=1e-6)
        assert np.all(np.diff(stamps) >= 0)
        assert np.isfinite(sim.sim.truth_pose()[0]).all()
    finally:
        ex.shutdown()
        sim.destroy_node()
        peer.destroy_node()


@pytest.mark.parametrize("path", ["compiled", "Python"])
def test_real_time_three_process_loop_both_paths(launcher, tmp_path, path):
    """sim (real time, compiled or Python path) -> estimator -> controller -> sim, + recorder, as
    separate processes at 100 Hz (slow enough for a busy machine): every joint state, tension
    sample and ground-truth pose is recorded (same stamps, on the period's grid, none lost), the
    commands answer them, and the platform follows the reference lifted from A (within 1 cm:
    stale commands on a loaded machine still hold it)."""
    import sys
    import time

    from cablelab.bags import open_bag

    bag_dir = tmp_path / "rt"
    if path == "Python":
        launcher.env["CABLELAB_NATIVE"] = "0"
    launcher.start("recorder", [sys.executable, "-m", "cablelab.cli", "record", "--plant", "cdpr",
                                "-o", bag_dir, "--quiet"])
    launcher.node("estimator", "payload_estimator", "cdpr", {})
    launcher.node("controller", "pd_feedforward", "cdpr", {})
    launcher.wait_for_topics({"/diagnostics": 2}, timeout=60)
    launcher.node("sim", "cable_sim_node", "cdpr", {"real_time": True, "rate": 100.0, "payload_mass": 249.0,
                                                    "duration": 8.0, "settle": 1.0,
                                                    "wait_for_subscribers": 2})
    deadline = time.monotonic() + 240
    while launcher.procs["sim"].alive() and time.monotonic() < deadline:
        time.sleep(0.5)
    assert not launcher.procs["sim"].alive(), "simulator did not finish 8 s of simulated time"
    time.sleep(3.0)
    codes = launcher.stop_all()
    assert codes["sim"] == 0, codes
    log = (launcher.log_dir / "sim.log").read_text()
    assert ("the Python per-period path" in log) == (path == "Python"), log

    bag = open_bag(bag_dir)
    js = bag.joint_state("/cdpr/joint_states", [f"winch_{i}" for i in range(1, 9)])
    ten = bag.joint_state("/cdpr/cable_tensions")
    cmd = bag.float_array("/cdpr/effort_commands")
    stamps = np.unique(np.round(js.t, 6))      # (the start state is published again by the start gate)
    assert stamps[-1] >= 7.99 and np.array_equal(stamps, np.unique(np.round(ten.t, 6)))
    np.testing.assert_allclose(stamps * 100.0, np.round(stamps * 100.0), atol=1e-6)
    assert len(stamps) == int(round(stamps[-1] * 100.0)) + 1           # none lost
    assert len(cmd.t) >= 0.9 * len(js.t)
    gt = bag.pose("/cdpr/ground_truth/pose")
    ref = bag.multidof_trajectory("/cdpr/reference")
    assert np.array_equal(np.unique(np.round(gt.t, 6)), stamps)
    z_ref = np.interp(gt.t, ref.t, ref.position[:, 2])
    sel = gt.t > 2.0
    assert np.abs(gt.position[sel, 2] - z_ref[sel]).max() < 0.01
    assert np.ptp(ref.position[:, 2]) > 0.1
