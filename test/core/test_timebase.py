"""cablelab.timebase against hand-built stamp sequences (closed-form answers) and a property:
segments partition the samples and no segment contains a step longer than a gap."""
from __future__ import annotations

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from cablelab.errors import CablelabError
from cablelab.timebase import Limits, check_stamps, gap_mask, raise_if_impossible

T = 1e-3


def test_clean_stamps_have_no_findings():
    t = np.arange(5000) * T + 3.0
    r = check_stamps(t, t, topic="/x")
    assert r.warnings() == [] and r.segments == [(0, 5000)] and r.period == pytest.approx(T)
    raise_if_impossible(r)


def test_gap_position_length_and_segments():
    t = np.arange(5000) * T
    keep = ~((t > 2.0) & (t < 2.5))
    r = check_stamps(t[keep], topic="/x")
    (g,) = r.gaps
    assert g.kind == "recording gap" and g.start == pytest.approx(2.0) and g.end == pytest.approx(2.5)
    assert g.duration == pytest.approx(0.5) and g.index == 2001
    assert r.segments == [(0, 2001), (2001, int(keep.sum()))]


def test_clock_jump_is_told_from_a_recording_gap_by_the_log_time():
    log = np.arange(3000) * T
    t = log.copy()
    t[1500:] += 0.3
    r = check_stamps(t, log, topic="/x")
    assert [g.kind for g in r.gaps] == ["clock jump"]


def test_backward_steps_duplicates_and_error_message():
    t = np.arange(1000) * T
    t[600:] -= 0.25                         # clock back 0.25 s
    t[100] = t[99]                          # one duplicate
    r = check_stamps(t, topic="/axis/joint_states")
    assert r.backward == 1 and r.backward_max == pytest.approx(0.25 - T) and r.duplicates == 1
    with pytest.raises(CablelabError) as exc:
        raise_if_impossible(r, "bag")
    msg = str(exc.value)
    assert "\n" not in msg and msg.startswith("bag: /axis/joint_states: header stamps go back in time 1 time")


def test_milliseconds_from_integer_stamps_and_from_log_span():
    ms = np.arange(2000, dtype=float)
    assert check_stamps(ms).milliseconds
    assert check_stamps(ms + 0.5e-3 * 0, ms * 1e-3).milliseconds
    assert not check_stamps(ms * 1e-3, ms * 1e-3).milliseconds
    with pytest.raises(CablelabError, match="milliseconds"):
        raise_if_impossible(check_stamps(ms))


def test_irregular_rate_and_nan_rows():
    t = np.arange(1000) * T
    t[500:] += np.arange(500) * 2.0 * T          # second half at a third of the rate: dt = 3T
    v = np.ones(1000)
    v[[10, 20]] = np.nan
    r = check_stamps(t, values=v, limits=Limits(gap_factor=5.0, rate_factor=2.0))
    assert r.irregular == 499 and r.nan_rows == 2 and not r.gaps


def test_gap_mask_widened_by_margin():
    t = np.arange(1000) * T
    keep = ~((t > 0.4) & (t < 0.6))
    r = check_stamps(t[keep])
    m = gap_mask(t, r.gaps, margin=0.05)
    expected = ~((t > r.gaps[0].start - 0.05) & (t < r.gaps[0].end + 0.05))
    np.testing.assert_array_equal(m, expected)


@settings(max_examples=60, deadline=None)
@given(steps=st.lists(st.sampled_from([1.0, 1.0, 1.0, 1.0, 1.2, 0.9, 7.0, 40.0]), min_size=3, max_size=300))
def test_segments_partition_and_contain_no_gap(steps):
    t = np.concatenate([[0.0], np.cumsum(steps)]) * T
    r = check_stamps(t)
    assert r.segments[0][0] == 0 and r.segments[-1][1] == t.size
    assert all(a[1] == b[0] for a, b in zip(r.segments[:-1], r.segments[1:]))
    for a, b in r.segments:
        if b - a > 1:
            assert np.max(np.diff(t[a:b])) <= 5.0 * r.period + 1e-15
    assert len(r.gaps) == int(np.sum(np.diff(t) > 5.0 * r.period))
