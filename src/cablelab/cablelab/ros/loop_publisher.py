"""The publisher process of a control loop: the period's samples, published off the loop's CPU path.

A control loop node (:mod:`cablelab.ros.control_loop`, parameter ``publisher:=process``) writes
each period's state and command into a :class:`~cablelab.sample_ring.SampleRing` in shared
memory and starts this module as a child process (:func:`start`). The child, at a lower CPU
priority (``niceness``), wakes every ``batch`` s, takes every record written since, in order, and
publishes each with the plant's cycle publisher (a class named ``package.module:Class`` whose
``publish(state, command, cycle)`` the loop would otherwise call in its own thread, e.g.
:class:`cablelab.plants.cdpr.nodes.control_loop.CdprCyclePublisher`). It ends when the loop
closes the ring (after publishing what is left and waiting, up to ``ack_wait`` s, until every
reliable subscriber acknowledged it) or when the loop's process is gone.

Run as ``python -m cablelab.ros.loop_publisher CONFIG_JSON [--ros-args ...]`` (the loop's own ROS
arguments, so that remappings apply to the child's publishers too). CONFIG_JSON keys: ``ring``
(shared-memory name), ``layout`` (:meth:`StateLayout.to_dict`), ``publisher`` (class spec),
``config`` (its configuration), ``node`` (node name), ``batch`` (s), ``niceness``, ``parent``
(pid of the loop), ``domain_id`` (the loop's ROS domain), ``match_wait`` (s, :func:`wait_for_matches`),
``ack_wait`` (s, :func:`wait_for_acks`; default 10).
"""
from __future__ import annotations

import importlib
import json
import os
import signal
import subprocess
import sys
import time

__all__ = ["start", "load_class", "wait_for_matches", "main"]


def load_class(spec: str):
    """The class named ``package.module:Class``."""
    module, _, name = spec.partition(":")
    obj = importlib.import_module(module)
    for part in name.split("."):
        obj = getattr(obj, part)
    return obj


def start(config: dict, ros_args: list[str], env: dict | None = None) -> subprocess.Popen:
    """Start the publisher process for ``config`` (module docstring); it receives SIGTERM if this
    process dies (Linux), so no orphan keeps publishing."""
    from .launch import _die_with_parent

    argv = [sys.executable, "-m", __name__, json.dumps(config), *ros_args]
    return subprocess.Popen(argv, env=env, preexec_fn=_die_with_parent if sys.platform.startswith("linux") else None)


def wait_for_matches(node, timeout: float, least: float = 0.5) -> bool:
    """Wait ``least`` s (discovery of the nodes already running), then until each of the node's
    publishers has matched every subscription the graph shows on its topic (e.g. a recorder
    started before the loop gets the first sample), at most ``timeout`` s in all. The loop keeps
    running meanwhile: its samples wait in the ring. False if some stayed unmatched."""
    start = time.monotonic()
    while True:
        now = time.monotonic() - start
        if now >= least and all(p.get_subscription_count() >= node.count_subscribers(p.topic_name)
                                for p in node.publishers):
            return True
        if now >= timeout:
            return False
        time.sleep(0.02)


def wait_for_acks(node, timeout: float) -> bool:
    """Wait up to ``timeout`` s until every matched reliable subscriber acknowledged every sample
    the node published: the writers' history ends with this process, and a recorder a few
    batches behind still needs its last samples. Whether all were acknowledged."""
    from rclpy.duration import Duration

    t_end = time.monotonic() + timeout
    return all([pub.wait_for_all_acked(Duration(seconds=max(0.0, t_end - time.monotonic())))
                for pub in node.publishers])


def run(config: dict, ros_args: list[str]) -> int:
    import rclpy
    from rclpy.node import Node
    from rclpy.signals import SignalHandlerOptions

    from ..sample_ring import SampleRing, StateLayout

    stop = []
    signal.signal(signal.SIGINT, signal.SIG_IGN)            # the loop ends us by closing the ring
    signal.signal(signal.SIGTERM, lambda *_: stop.append(1))  # the loop's process died: drain, end
    nice = int(config.get("niceness", 0))
    if nice > 0:
        # this process only (its threads start later and inherit it); not fastspin.set_background,
        # which also lowers the session's autogroup: the loop's own process is in that group
        os.nice(nice)
    ring = SampleRing.attach(config["ring"])
    layout = StateLayout.from_dict(config["layout"])
    rclpy.init(args=["loop_publisher", *ros_args], signal_handler_options=SignalHandlerOptions.NO,
               domain_id=config.get("domain_id"))
    node = Node(config["node"])
    publisher = load_class(config["publisher"])(node, config["config"])
    parent, batch = int(config["parent"]), float(config["batch"])
    wait_for_matches(node, float(config.get("match_wait", 2.0)))
    cycle, cpu0 = 0, None
    try:
        while True:
            ending = ring.closed or bool(stop) or os.getppid() != parent
            rows = ring.take()
            if len(rows):
                if cpu0 is None:
                    cpu0, first = time.process_time(), cycle
                for row in rows:
                    state, command = layout.unpack(row)
                    publisher.publish(state, command, cycle)
                    cycle += 1
                ring.report_cost(time.process_time() - cpu0, cycle - first)
            if ending and ring.backlog == 0:
                break
            time.sleep(batch)
        wait_for_acks(node, float(config.get("ack_wait", 10.0)))
    finally:
        node.destroy_node()
        rclpy.try_shutdown()
        ring.release()
    return 0


def main(argv: list[str] | None = None) -> int:
    argv = sys.argv[1:] if argv is None else argv
    if not argv:
        print("usage: python -m cablelab.ros.loop_publisher CONFIG_JSON [--ros-args ...]", file=sys.stderr)
        return 2
    return run(json.loads(argv[0]), argv[1:])


if __name__ == "__main__":
    sys.exit(main())
