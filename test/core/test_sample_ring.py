"""The control loop's shared-memory ring (cablelab.sample_ring): every record put is taken once,
in order, across processes; a full ring refuses and counts, never overwrites; the state layout
packs and unpacks a HardwareState exactly."""
from __future__ import annotations

import subprocess
import sys
from collections import deque

import numpy as np
import pytest
from hypothesis import given, settings, strategies as st

from cablelab.hardware import HardwareState
from cablelab.sample_ring import SampleRing, StateLayout


@pytest.fixture
def ring_factory():
    made = []

    def make(width, capacity):
        r = SampleRing.create(width, capacity)
        made.append(r)
        return r
    yield make
    for r in made:
        r.release()


@settings(max_examples=60, deadline=None)
@given(capacity=st.integers(2, 9),
       ops=st.lists(st.one_of(st.tuples(st.just("put"), st.integers(1, 7)),
                              st.tuples(st.just("take"), st.one_of(st.none(), st.integers(0, 6)))), max_size=60))
def test_ring_against_a_bounded_queue(capacity, ops):
    """Any sequence of puts and takes behaves as a bounded FIFO that refuses when full (oracle:
    a deque with the same capacity), through the wrap-around of the slots."""
    ring = SampleRing.create(3, capacity)
    try:
        oracle, lost, counter = deque(), 0, 0
        for op, arg in ops:
            if op == "put":
                for _ in range(arg):
                    rec = [counter, -counter, 0.5 * counter]
                    counter += 1
                    ok = ring.put(rec)
                    assert ok == (len(oracle) < capacity)
                    if ok:
                        oracle.append(rec)
                    else:
                        lost += 1
            else:
                got = ring.take(arg)
                k = len(oracle) if arg is None else min(arg, len(oracle))
                want = [oracle.popleft() for _ in range(k)]
                np.testing.assert_array_equal(got.reshape(-1, 3), np.array(want, float).reshape(-1, 3))
            assert ring.backlog == len(oracle) and ring.lost == lost
    finally:
        ring.release()


CONSUMER = r"""
import sys, time
import numpy as np
from cablelab.sample_ring import SampleRing
ring = SampleRing.attach(sys.argv[1])
seen = []
while True:
    closed = ring.closed
    rows = ring.take()
    seen.extend(rows[:, 0].tolist())
    assert (rows[:, 1] == 2.0 * rows[:, 0]).all() and (rows[:, 2:] == rows[:, :1]).all(), "torn record"
    if closed and ring.backlog == 0:
        break
    time.sleep(0.001)
ring.report_cost(time.process_time(), len(seen))
ring.release()
print(len(seen), int(np.all(np.diff(seen) == 1)), int(seen[0]) if seen else -1)
"""


def test_ring_across_processes(ring_factory):
    """A producer writing 50 000 records as fast as it can and a consumer process taking them in
    batches: every record arrives once, whole and in order, none refused (ring of 60 000), and
    the consumer's reported cost reaches the producer."""
    ring = ring_factory(6, 60_000)
    child = subprocess.Popen([sys.executable, "-c", CONSUMER, ring.name], stdout=subprocess.PIPE, text=True)
    rec = np.zeros(6)
    for k in range(50_000):
        row = ring.slot()
        assert row is not None
        rec[:] = k
        rec[1] = 2.0 * k
        row[:] = rec
        ring.commit()
    ring.close()
    out, _ = child.communicate(timeout=120)
    assert child.returncode == 0
    n, in_order, first = map(int, out.split())
    assert (n, in_order, first) == (50_000, 1, 0)
    assert ring.taken == ring.written == 50_000 and ring.lost == 0
    assert ring.consumer_cpu_per_record is not None and ring.consumer_cpu_per_record > 0.0


def test_full_ring_refuses_and_counts(ring_factory):
    ring = ring_factory(2, 4)
    assert all(ring.put([k, k]) for k in range(4))
    assert ring.slot() is None and not ring.put([9, 9]) and ring.lost == 2
    np.testing.assert_array_equal(ring.take(1), [[0.0, 0.0]])
    assert ring.put([4, 4])
    np.testing.assert_array_equal(ring.take()[:, 0], [1, 2, 3, 4])     # the refused ones never appear


def test_state_layout_round_trip(ring_factory):
    """pack then unpack gives back the stamp, the joint arrays, the extras and the command bit for
    bit; a missing command comes back None, a missing extra is left out, an unknown one ignored."""
    rng = np.random.default_rng(0)
    n = 5
    state = HardwareState(12.345678901234, rng.normal(size=n), rng.normal(size=n), rng.normal(size=n),
                          {"tension": rng.normal(size=n), "quat": rng.normal(size=4)})
    layout = StateLayout.of(state)
    assert layout.width == 1 + 3 * n + n + 4 + n + 1
    assert StateLayout.from_dict(layout.to_dict()) == layout
    ring = ring_factory(layout.width, 3)
    cmd = rng.normal(size=n)
    for command in (cmd, None):
        row = ring.slot()
        layout.pack(row, state, command)
        ring.commit()
    # a measured NaN is kept: an extra is left out only when all its values are NaN
    other = HardwareState(1.0, np.ones(n), np.ones(n), np.ones(n),
                          {"quat": np.array([np.nan, 1.0, np.nan, 1.0]), "unknown": np.ones(2)})
    layout.pack(ring.slot(), other, cmd)
    ring.commit()
    rows = ring.take()
    for row, command in zip(rows[:2], (cmd, None)):
        s, c = layout.unpack(row)
        assert s.t == state.t
        for name in ("position", "velocity", "effort"):
            np.testing.assert_array_equal(getattr(s, name), getattr(state, name))
        assert s.extra.keys() == state.extra.keys()
        for k in s.extra:
            np.testing.assert_array_equal(s.extra[k], state.extra[k])
        if command is None:
            assert c is None
        else:
            np.testing.assert_array_equal(c, command)
    s, _ = layout.unpack(rows[2])
    assert set(s.extra) == {"quat"}
    np.testing.assert_array_equal(s.extra["quat"], [np.nan, 1.0, np.nan, 1.0])
