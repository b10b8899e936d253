"""The three leg nodes in one process on a private ROS domain: simulator -> estimator ->
controller closed over DDS; the estimate shows both phases and finite apexes, the controller
answers with torques, and the estimator reports a missing contact switch on /diagnostics."""
from __future__ import annotations

import math
import time

import pytest


@pytest.fixture
def ros_context(domain_id):
    import rclpy

    rclpy.init(domain_id=domain_id)
    yield
    rclpy.try_shutdown()


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
