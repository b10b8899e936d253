"""The lead-in of a designed reference (:func:`cablelab.excite.lead_in`): from any start at rest
to the centre of the limits' box at rest, and the fastest such quintic move: its peak speed or
acceleration meets the limit of one joint and exceeds none (the peaks measured on a fine
sampling, against the limits, not the formula)."""
import numpy as np
from hypothesis import given, settings
from hypothesis import strategies as st

from cablelab.excite import Limits, lead_in

coord = st.floats(-3.0, 3.0)
positive = st.floats(0.05, 2.0)


@settings(max_examples=40, deadline=None)
@given(st.tuples(coord, coord), st.tuples(positive, positive), st.tuples(positive, positive),
       st.tuples(st.floats(0.5, 3.0), st.floats(0.5, 3.0)))
def test_lead_in_reaches_the_centre_at_rest_at_the_limits(start, speed, accel, half):
    lim = Limits(("a", "b"), -np.array(half), np.array(half), np.array(speed), np.array(accel))
    length, fn = lead_in(start, lim, 100.0)
    assert abs(length * 100 - round(length * 100)) < 1e-9                    # on the rate's grid
    t = np.linspace(0.0, length, 20001)
    q, qd, qdd = fn(t)
    np.testing.assert_allclose(q[0], start, atol=1e-12)
    np.testing.assert_allclose(q[-1], 0.0, atol=1e-12)
    assert np.abs(qd[[0, -1]]).max() < 1e-12 and np.abs(qdd[[0, -1]]).max() < 1e-9
    use = np.maximum(np.abs(qd).max(axis=0) / lim.speed, np.abs(qdd).max(axis=0) / lim.accel).max()
    assert use <= 1.0 + 1e-6
    # rounding the length up to the 10 ms grid costs at most that much of the peak use
    shorter = length - 0.01
    assert length < 0.02 or use >= (shorter / length) ** 2 - 1e-6


def test_no_move_when_starting_at_the_centre():
    lim = Limits(("a",), np.array([-1.0]), np.array([1.0]), np.array([0.5]), np.array([0.5]))
    length, fn = lead_in([0.0], lim, 100.0)
    assert length == 0.0
    q, qd, qdd = fn(np.array([0.0]))
    assert q.tolist() == [[0.0]] and qd.tolist() == [[0.0]] and qdd.tolist() == [[0.0]]
