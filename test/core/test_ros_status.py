"""The nodes' /diagnostics book-keeping (cablelab/ros/status.py), ROS-free."""
import numpy as np

from cablelab.ros.status import Latency, SkipLog, add_problem


def test_problems_join_into_one_line_at_the_worst_level():
    assert add_problem(0, "ok", 1, "slack cable(s) 3") == (1, "slack cable(s) 3")
    assert add_problem(2, "stale input: x", 1, "slack") == (2, "stale input: x; slack")


def test_a_recent_skip_warns_with_its_reason(monkeypatch):
    import cablelab.ros.status as status

    now = [100.0]
    monkeypatch.setattr(status.time, "monotonic", lambda: now[0])
    log = SkipLog(recent=2.0)
    assert log.skip("no fresh reference") is None and log.skipped == 1
    assert log.warn(0, "ok") == (1, "no fresh reference")
    now[0] += 2.5
    assert log.warn(0, "ok") == (0, "ok") and log.last_problem == "no fresh reference"


def test_latency_p99_over_the_last_1000_samples_and_bounded():
    lat = Latency(keep=3000)
    assert lat.report({}) == {}
    x = np.r_[np.full(5000, 1.0), np.linspace(0.0, 1e-3, 1000)]
    for v in x:
        lat.add(v)
    assert len(lat) <= 3000
    assert lat.report({})["latency p99 ms"] == f"{1000 * np.percentile(x[-1000:], 99):.3f}"
