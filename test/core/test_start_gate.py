"""The simulators' start gate (PlantNode.waiting_for_subscribers) against scripted DDS answers:
time must not start on the writer's subscriber count alone (the subscriber may match seconds
later and drop every sample until then), but on the acknowledgement of a sample published after
the count was reached; and nothing may be published while the acknowledgements are awaited
(they come with the writer's periodic heartbeat: a new sample each half second would keep a
writer unacknowledged, which kept a crane run waiting 60 s)."""
from __future__ import annotations

import types

import pytest

from cablelab.ros import plant_node
from cablelab.ros.plant_node import PROBE_REPEAT, PlantNode


class FakePublisher:
    """A writer: its subscriber count, and whether everything published was acknowledged
    (a new sample is unacknowledged until ``ack()``)."""

    def __init__(self):
        self.count, self.acked = 0, True

    def get_subscription_count(self):
        return self.count

    def wait_for_all_acked(self, timeout):
        return self.acked

    def ack(self):
        self.acked = True


class FakeLogger:
    def __init__(self):
        self.lines = []

    def info(self, msg):
        self.lines.append(msg)

    warning = info


@pytest.fixture
def clock(monkeypatch):
    """The gate's wall clock, set by the test: ``clock[0]`` s."""
    now = [0.0]
    monkeypatch.setattr(plant_node.time, "monotonic", lambda: now[0])
    return now


def make_gate(clock, wait_subs=2):
    state, other, diag = FakePublisher(), FakePublisher(), FakePublisher()
    published = []

    def republish():
        published.append(clock[0])
        state.acked = other.acked = False
        diag.acked = False          # a diagnostics sample never acknowledged: not counted

    log = FakeLogger()
    node = types.SimpleNamespace(wait_subs=wait_subs, probe_sent=None, created=clock[0],
                                 publishers=[state, other, diag], diag=types.SimpleNamespace(pub=diag),
                                 get_logger=lambda: log)
    node.all_acknowledged = lambda: PlantNode.all_acknowledged(node)

    def waiting(last_publish):
        return PlantNode.waiting_for_subscribers(node, state, last_publish, republish, every=0.5)
    return node, state, other, published, waiting, log


def test_gate_waits_for_the_acknowledgement_of_a_sample_published_after_the_count(clock):
    clock[0] = 100.0
    node, state, other, published, waiting, log = make_gate(clock)

    # too few subscribers: the start state is republished every 0.5 s for late joiners
    for k in range(10):
        clock[0] = 100.0 + 0.2 * k
        assert waiting(published[-1] if published else 100.0)
    assert len(published) == 3                       # at 100.6, 101.2, 101.8
    state.ack(), other.ack()                         # (earlier samples: acknowledged or irrelevant)

    # the count is reached: everything so far counts as acknowledged, yet time must not start
    state.count = 2
    clock[0] = 102.0
    assert waiting(published[-1])
    assert published[-1] == 102.0                    # the probe
    n_probe = len(published)
    # no acknowledgement yet: wait, and publish nothing (each new sample would need a heartbeat)
    for k in range(1, 60):
        clock[0] = 102.0 + 0.1 * k                   # up to 107.9 s
        assert waiting(published[-1])
        if clock[0] - 102.0 <= PROBE_REPEAT:
            assert len(published) == n_probe
    assert len(published) == n_probe + 1             # the probe repeated once after PROBE_REPEAT s
    # one writer acknowledged, the other not: still waiting
    state.ack()
    clock[0] += 0.1
    assert waiting(published[-1])
    # both acknowledged (the never-acknowledged /diagnostics does not count): time starts
    other.ack()
    clock[0] += 0.1
    assert not waiting(published[-1])
    assert node.wait_subs == 0 and "acknowledged" in log.lines[-1]
    assert not waiting(published[-1])                # and stays started


def test_gate_gives_up_after_60_s_with_a_warning(clock):
    node, state, other, published, waiting, log = make_gate(clock)
    state.count = 2
    clock[0] = 59.9
    assert waiting(0.0)                              # the probe is never acknowledged
    clock[0] = 60.0
    assert not waiting(published[-1])
    assert "without" in log.lines[-1]


def test_gate_restarts_the_probe_when_a_subscriber_leaves(clock):
    node, state, other, published, waiting, log = make_gate(clock)
    state.count = 2
    clock[0] = 1.0
    assert waiting(0.0) and node.probe_sent == 1.0
    state.count = 1                                  # one went away before acknowledging
    clock[0] = 1.1
    assert waiting(published[-1]) and node.probe_sent is None
    state.count = 2
    clock[0] = 1.2
    assert waiting(published[-1]) and node.probe_sent == 1.2   # a new probe for the new match
    state.ack(), other.ack()
    clock[0] = 1.3
    assert not waiting(published[-1])
