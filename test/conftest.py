"""Shared pytest fixtures: a unique ROS_DOMAIN_ID per test and a process launcher."""
from __future__ import annotations

import itertools
import os

import pytest

_counter = itertools.count()


def _domain_id() -> int:
    """1..200, distinct across concurrently running test sessions (pid) and tests (counter)."""
    return 1 + (os.getpid() * 13 + next(_counter) * 37) % 200


@pytest.fixture
def domain_id() -> int:
    return _domain_id()


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
