"""The three leg nodes in one process on a private ROS domain: simulator -> estimator ->
controller closed over DDS; the estimate shows both phases and finite apexes, the controller
answers with torques, and the estimator reports a missing contact switch on /diagnostics."""
from __future__ import annotations

import math
import time

import numpy as np
import pytest


def _spin(nodes, seconds, until=None):
    """Spin for ``seconds`` of wall time, or, with ``until``, until it holds (checked every
    0.5 s; ``seconds`` is then the limit: a loaded machine runs the simulator slower)."""
    from rclpy.executors import SingleThreadedExecutor

    ex = SingleThreadedExecutor()
    for n in nodes:
        ex.add_node(n)
    end = time.monotonic() + seconds
    check = time.monotonic() + 0.5
    while time.monotonic() < end:
        ex.spin_once(timeout_sec=0.001)
        if until is not None and time.monotonic() > check:
            if until():
                break
            check = time.monotonic() + 0.5
    for n in nodes:
        ex.remove_node(n)


def test_closed_loop_over_dds(ros_context):
    from rclpy.node import Node
    from sensor_msgs.msg import JointState
    from std_msgs.msg import Float64MultiArray

    from cablelab.plants.leg.nodes import controller, estimator, sim
    from cablelab.ros.qos import stream_qos

    nodes = [m.make_node() for m in (sim, estimator, controller)]
    probe = Node("probe")
    est, cmd = [], []
    probe.create_subscription(JointState, "/leg/hop_estimate", est.append, stream_qos())
    probe.create_subscription(Float64MultiArray, "/leg/effort_commands", cmd.append, stream_qos())

    def hopped() -> bool:      # both phases, an apex and stance torques seen
        return (len(est) > 200 and len(cmd) > 200 and {round(m.position[1]) for m in est} == {0, 1}
                and any(math.isfinite(m.position[2]) for m in est)
                and any(abs(m.data[0]) > 0.1 for m in cmd))

    _spin(nodes + [probe], 120.0, until=hopped)
    assert len(est) > 200 and len(cmd) > 200
    phases = {round(m.position[1]) for m in est}
    assert phases == {0, 1}
    assert any(math.isfinite(m.position[2]) for m in est)  # an apex was estimated
    assert any(abs(m.data[0]) > 0.1 for m in cmd)  # stance torques were commanded
    status, _, values = nodes[1].status()
    assert values["phase source"] == "contact switch"
    for n in nodes + [probe]:
        n.destroy_node()


def test_estimator_without_contact_says_so(ros_context):
    from cablelab.plants.leg.nodes.estimator import make_node

    node = make_node()
    level, msg, values = node.status()
    assert "phase from height" in msg and values["phase source"].startswith("height")
    node.destroy_node()


@pytest.mark.parametrize("state_first", [True, False])
def test_estimator_pairs_each_state_with_its_samples_switch(ros_context, state_first):
    """The state and the switch reading of a sample come on two topics in either order; the
    node's estimates equal those of the ROS-free estimator fed each sample with its own switch
    reading (oracle: :class:`HopEstimator` on the simulated run), touch-downs included."""
    from cablelab.plants.leg.estimator import HopEstimator
    from cablelab.plants.leg.excite import closed_loop
    from cablelab.plants.leg.hybrid import LegParams
    from cablelab.plants.leg.nodes.estimator import make_node
    from cablelab.ros import convert

    p = LegParams()
    run = closed_loop(p, p.z_td + 0.012, 1.5, z0=p.z_td + 0.03, seed=None)
    node = make_node()
    out = []
    node.pub = type("Pub", (), {"publish": staticmethod(out.append)})()
    for t, z, c, tau in zip(run.t, run.z_meas, run.contact, run.tau):
        state = convert.joint_state_msg(t, ["body", "motor"], [z, 0.0], [0.0, 0.0], [0.0, tau])
        switch = convert.joint_state_msg(t, ["contact"], [c])
        for msg, cb in ((state, node.on_state), (switch, node.on_contact))[:: 1 if state_first else -1]:
            cb(msg)
    node.destroy_node()
    ref = HopEstimator(p)
    want = [ref.step(t, z, c, tau) for t, z, c, tau in zip(run.t, run.z_meas, run.contact, run.tau)]
    assert len(out) == len(want)
    got = np.array([[convert.joint_state_arrays(m)[0], m.position[1], m.position[2]] for m in out])
    exp = np.array([[t, e.phase, e.apex_height] for t, e in zip(run.t, want)])
    np.testing.assert_allclose(got[:, 0], exp[:, 0], rtol=0, atol=1e-9)
    assert np.array_equal(got[:, 1], exp[:, 1])              # every sample's phase: touch-downs on time
    np.testing.assert_allclose(got[:, 2], exp[:, 2], rtol=0, atol=1e-12, equal_nan=True)
    assert {0, 1} <= set(got[:, 1].astype(int))
