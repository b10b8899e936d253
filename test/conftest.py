"""Shared pytest fixtures: a unique ROS_DOMAIN_ID per test and a process launcher."""
from __future__ import annotations

import itertools

import pytest

_counter = itertools.count()


@pytest.fixture
def domain_id():
    """A ROS_DOMAIN_ID in 1..200 no other process on this machine holds during the test
    (locked: concurrent test sessions, demos and benchmarks never share one)."""
    from cablelab.ros.launch import release_domain_id, reserve_domain_id

    d = reserve_domain_id(salt=next(_counter))
    try:
        yield d
    finally:
        release_domain_id(d)


@pytest.fixture
def ros_context(domain_id):
    """rclpy initialised on the test's own domain, for nodes built in the test's process."""
    import rclpy

    rclpy.init(domain_id=domain_id)
    yield
    rclpy.try_shutdown()


@pytest.fixture
def launcher(tmp_path, domain_id):
    """A :class:`cablelab.ros.launch.Launcher` on a fresh domain; stops everything at the end and
    prints the process logs of a failed test."""
    from cablelab.ros.launch import Launcher

    launch = Launcher(domain_id=domain_id, log_dir=tmp_path / "logs")
    try:
        yield launch
    finally:
        launch.stop_all(grace=10.0)
        for proc in launch.procs.values():
            text = proc.log().strip()
            if text:
                print(f"----- {proc.name} (exit {proc.popen.returncode})\n{text[-3000:]}")


@pytest.fixture
def diagnostics_seen(launcher):
    """``(probe, seen)``: a probe node of ``launcher`` listening on /diagnostics; ``seen[name]`` is
    the newest status of that name as ``(level, message, {key: value}, time.monotonic() of arrival)``
    once the probe's executor has spun."""
    import time

    from diagnostic_msgs.msg import DiagnosticArray

    probe = launcher.probe()
    seen = {}

    def on_diag(msg):
        for st in msg.status:
            seen[st.name] = (int.from_bytes(st.level, "little") if isinstance(st.level, bytes) else int(st.level),
                             st.message, {kv.key: kv.value for kv in st.values}, time.monotonic())
    probe.node.create_subscription(DiagnosticArray, "/diagnostics", on_diag, 50)
    return probe, seen


@pytest.fixture
def play_designed(launcher, tmp_path):
    """``run(plant, description, params, nodes, counts, joints, ...)``: design an excitation of
    ``params`` (``cablelab.excite.design``), write it as a reference bag, record the plant over DDS
    (the recorder, then ``nodes``: (role, executable, parameters) each, then ``pd_feedforward``
    playing the bag through its ``reference_bag`` parameter, and ``controller``'s other
    parameters) until ``counts`` messages per topic
    are recorded, and check every process exits 0. Returns ``(bag, played, want, desc)``: the
    recorded bag, its reference on the exciter's topic (``joints``; ``t`` and ``positions``, a
    platform's x, y, z for a pose reference), the bag's reference at the
    same times since the first played sample, and the loaded description."""
    import sys
    from types import SimpleNamespace

    from cablelab.bags import open_bag
    from cablelab.description import load_description
    from cablelab.excite import design, get_exciter, read_reference, write_reference

    def run(plant, description, params, nodes, counts, joints, duration=12.0, max_iter=5, timeout=180,
            controller=None):
        desc = load_description(description)
        exciter = get_exciter(plant)
        ref = tmp_path / "ref"
        write_reference(ref, design(plant, desc, params, duration=duration, max_iter=max_iter), exciter,
                        description)
        bag_dir = tmp_path / "run"
        launcher.start("recorder", [sys.executable, "-m", "cablelab.cli", "record", "--plant", plant,
                                    "-o", bag_dir, "--quiet"])
        launcher.wait_for_subscribers([f"/{plant}/joint_states", exciter.reference_topic], timeout=120,
                                      node_name="cablelab_recorder")
        for role, executable, parameters in nodes:
            launcher.node(role, executable, plant, parameters)
        launcher.node("controller", "pd_feedforward", plant, {"reference_bag": str(ref), **(controller or {})})
        launcher.wait_for_recorded(bag_dir, counts, timeout=timeout)
        codes = launcher.stop_all()
        assert set(codes.values()) == {0} and "controller" in codes, codes
        bag = open_bag(bag_dir)
        if exciter.trajectory == "pose":      # a platform's x, y, z (MultiDOFJointTrajectory)
            tr = bag.multidof_trajectory(exciter.reference_topic)
            played = SimpleNamespace(t=tr.t, positions=tr.position)
        else:
            played = bag.joint_trajectory(exciter.reference_topic, joints)
        want = read_reference(ref, exciter.reference_topic, joints)(played.t - played.t[0])[0]
        return bag, played, want, desc

    return run
