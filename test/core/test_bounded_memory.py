"""Every memory- or time-proportional step is bounded by the data, not by its stamps: a forward
clock jump of 1e6 s in a 20 s bag neither makes the resampling grid span the gap (identify ran
out of memory) nor makes replay wait through it (about 10 000 s); a description file is read
only if it is a regular file of at most 16 MiB (``/dev/zero`` was read without end)."""
from __future__ import annotations

import os
import resource
import subprocess
import sys

import numpy as np
import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from robust_helpers import EMPS, REPO

from cablelab.conditioning import GAP_PERIODS, segment_grid, uniform_grid
from cablelab.pacing import replay_times

FUZZ = settings(max_examples=int(os.environ.get("CABLELAB_FUZZ_EXAMPLES", "12")) * 4, deadline=None,
                derandomize=not os.environ.get("CABLELAB_FUZZ_RANDOM"),
                suppress_health_check=[HealthCheck.function_scoped_fixture])


def _jump_bag(path, jump=1e6):
    """The EMPS bag (24.8 s at 1 kHz) with its stamps after t = 10 s moved ``jump`` s later."""
    from cablelab.bags import BagWriter, open_bag

    b = open_bag(EMPS)
    js = b.joint_state("/axis/joint_states")
    t = js.t.copy()
    t[t > 10] += jump
    with BagWriter(path) as w:
        w.write_description(b.description_yaml, t=0.0)
        w.write_joint_states("/axis/joint_states", t, js.names, js.position, js.velocity, js.effort)
    return path


# ----------------------------------------------------------------------------- resampling grid
def test_grid_never_spans_a_clock_jump():
    """Irregular 1 kHz stamps with a 1e6 s jump: the grid has about N points, uniform within each
    segment, and the signal on it is the linear interpolation inside each segment."""
    rng = np.random.default_rng(0)
    t = np.cumsum(rng.uniform(0.0008, 0.0012, 20000))
    t[10000:] += 1e6
    x = np.sin(t)
    tu, (xu,) = uniform_grid(t, x)
    assert tu.size < 1.3 * t.size
    assert not np.any((tu > t[9999] + 0.01) & (tu < t[10000] - 0.01))     # nothing in the gap
    for seg in (tu < 1e5, tu > 1e5):
        d = np.diff(tu[seg])
        assert np.allclose(d, d[0], rtol=1e-6, atol=1e-9)
    inside = tu < 1e5
    assert np.allclose(xu[inside], np.interp(tu[inside], t[:10000], x[:10000]))


@FUZZ
@given(n=st.integers(20, 3000), jumps=st.lists(st.tuples(st.floats(0.0, 1.0), st.floats(-3.0, 9.0)),
                                                max_size=6), seed=st.integers(0, 2**31))
def test_fuzz_grid_bounded_by_sample_count(n, jumps, seed):
    """Random forward clock jumps of 10^-3 .. 10^9 s: the grid has at most GAP_PERIODS x N +
    segments points, is increasing and covers every sample time's segment."""
    rng = np.random.default_rng(seed)
    dt = rng.uniform(0.9e-3, 1.1e-3, n - 1)
    for where, logj in jumps:
        dt[int(where * (n - 2))] += 10.0 ** logj
    t = np.concatenate([[0.0], np.cumsum(dt)])
    rate = 1.0 / np.median(np.diff(t))
    tu = segment_grid(t, rate)
    segments = 1 + int(np.sum(np.diff(t) > GAP_PERIODS / rate))
    assert tu.size <= GAP_PERIODS * n + segments
    assert np.all(np.diff(tu) > 0)
    assert tu[0] == t[0] and tu[-1] <= t[-1] + 1e-9
    # every sample is within one grid period of a grid point (the grid covers the data)
    k = np.clip(np.searchsorted(tu, t), 1, tu.size - 1)
    near = np.minimum(np.abs(tu[k] - t), np.abs(tu[k - 1] - t))
    assert np.all(near <= 1.0 / rate + 1e-9)


def test_identify_across_a_clock_jump_is_bounded(tmp_path):
    """`identify` of a 20 s bag with a 1e6 s forward jump under a 1.5 GB address-space limit:
    succeeds, warns about the gap, and finds the parameters of the clean bag (the jump only
    splits the record into two segments)."""
    bag = _jump_bag(tmp_path / "jump")

    def limit():
        resource.setrlimit(resource.RLIMIT_AS, (3 * 2**30, 3 * 2**30))

    def identify(b):
        r = subprocess.run([sys.executable, "-m", "cablelab.cli", "identify", str(b), "--json"],
                           capture_output=True, text=True, timeout=600, preexec_fn=limit, cwd=REPO)
        assert r.returncode == 0, r.stderr[-2000:]
        import json

        return json.loads(r.stdout)

    got, clean = identify(bag), identify(EMPS)
    assert any("gap" in w for w in got["warnings"]), got["warnings"]
    for name, v in clean["params"].items():
        assert got["params"][name]["value"] == pytest.approx(v["value"], rel=0.15), name


# ----------------------------------------------------------------------------- replay pacing
def test_replay_schedule_shortens_gaps():
    t = (np.arange(2000) * 1_000_000).astype(np.int64)          # 1 kHz, in ns
    t[1000:] += int(1e6 * 1e9)                                  # +1e6 s
    due, gaps = replay_times(t)
    assert gaps.count == 1 and gaps.longest == pytest.approx(1e6, rel=1e-6)
    assert (due[-1] - due[0]) * 1e-9 == pytest.approx(1.999, abs=1e-6)   # as if no jump
    assert np.all(np.diff(due) > 0)
    assert np.array_equal(np.diff(due[:1000]), np.diff(t[:1000]))        # pacing kept elsewhere
    due2, gaps2 = replay_times(t[:1000])
    assert gaps2.count == 0 and np.array_equal(due2, t[:1000])


@FUZZ
@given(steps=st.lists(st.floats(1e-4, 1e7), min_size=1, max_size=200))
def test_fuzz_replay_duration_bounded_by_messages(steps):
    """Whatever the log times, the replay lasts at most max(GAP_PERIODS x median step, 1 s)
    per message, and never longer than the recording."""
    t = np.concatenate([[0], np.cumsum(np.asarray(steps) * 1e9)]).astype(np.int64)
    due, gaps = replay_times(t)
    assert np.all(np.diff(due) >= 0)
    assert due[-1] - due[0] <= t[-1] - t[0]
    assert due[-1] - due[0] <= (len(t) - 1) * max(gaps.threshold_ns, 1)


def test_replay_does_not_wait_through_a_clock_jump(tmp_path, domain_id):
    """In process: a 2 s bag with a 1e6 s jump is replayed in about 2 s, /clock jumps."""
    import time as _time

    import rclpy
    from rclpy.executors import SingleThreadedExecutor

    from cablelab.bags import BagWriter
    from cablelab.ros.replayer import ReplayNode

    t = np.arange(200) * 0.01
    t[100:] += 1e6
    with BagWriter(tmp_path / "b") as w:
        w.write_joint_states("/axis/joint_states", t, ["joint"], np.zeros((200, 1)))
    rclpy.init(domain_id=domain_id)
    try:
        node = ReplayNode(tmp_path / "b", rate=1.0, start_delay=0.0, quiet=True)
        assert node.gaps.count == 1
        ex = SingleThreadedExecutor()
        ex.add_node(node)
        t0 = _time.monotonic()
        while not node.done and _time.monotonic() - t0 < 60:
            ex.spin_once(timeout_sec=0.05)
        assert node.done and node.published == 200
        sent = np.array(node.sent_wall) - node.t0_wall
        assert sent[-1] < 30.0
        assert sent[99] >= 0.99 - 1e-6                  # paced before the jump
        # clock published at 100 Hz of bag time: about 200 messages, not 1e8
        assert node.next_clock * 1e-9 == pytest.approx(t[-1], abs=0.02)
        node.destroy_node()
    finally:
        rclpy.try_shutdown()


@FUZZ
@given(n=st.integers(1, 500), gaps=st.lists(st.tuples(st.floats(-5, 105), st.floats(0, 20)), max_size=40),
       margin=st.floats(0, 3))
def test_fuzz_gap_mask_is_the_interval_test(n, gaps, margin):
    """The gap mask (searchsorted, O(N log G) memory O(N + G)) equals the direct (N, G) test."""
    from cablelab.timebase import Gap, gap_mask

    t = np.sort(np.random.default_rng(n).uniform(0, 100, n))
    gl = [Gap(0, a, a + d, "recording gap") for a, d in gaps]
    lo = np.array([g.start for g in gl]) - margin
    hi = np.array([g.end for g in gl]) + margin
    want = ~((t[:, None] > lo[None, :]) & (t[:, None] < hi[None, :])).any(axis=1) if gl else np.ones(n, bool)
    assert np.array_equal(gap_mask(t, gl, margin), want)


def test_gap_mask_of_many_gaps_is_small():
    """10^6 samples, 10^5 gaps: the mask costs O(N + G), not an (N, G) matrix of 10^11 bools."""
    from cablelab.timebase import Gap, gap_mask

    t = np.arange(1_000_000) * 1e-3
    gl = [Gap(0, a, a + 2e-3, "recording gap") for a in np.arange(100_000) * 1e-2]
    keep = gap_mask(t, gl, 0.0)
    assert keep.shape == t.shape and 0 < (~keep).sum() < t.size
