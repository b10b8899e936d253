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
