"""InputMonitor.accept_rows (k messages checked at once, as the CDPR controller does with the
reference samples its compiled thread took) against its oracle, k calls of InputMonitor.accept."""
from __future__ import annotations

import numpy as np
from hypothesis import given, settings, strategies as st

from cablelab.ros.inputs import InputMonitor

VALUES = st.sampled_from([0.0, -1.5, 2.0e3, np.nan, np.inf, -np.inf])


@settings(max_examples=200, deadline=None)
@given(data=st.data(), k=st.integers(0, 12), m=st.integers(0, 4), length=st.sampled_from([None, 3]),
       with_present=st.booleans(), before=st.sampled_from(["", "stale"]))
def test_accept_rows_equals_accept_of_each_row(data, k, m, length, with_present, before):
    rows = np.array(data.draw(st.lists(st.lists(VALUES, min_size=m, max_size=m), min_size=k, max_size=k)),
                    float).reshape(k, m)
    present = np.array(data.draw(st.lists(st.booleans(), min_size=k, max_size=k)), bool) if with_present else None
    one, many = InputMonitor(), InputMonitor()
    for mon in (one, many):
        mon.add("reference", timeout=0.5, length=length)
        mon.inputs["reference"].last_problem = before
    want = np.array([one.accept("reference", None if present is not None and not present[i] else rows[i], 7.0)
                     for i in range(k)], bool)
    got = many.accept_rows("reference", rows, 7.0, present)
    np.testing.assert_array_equal(got, want)
    assert many.inputs["reference"] == one.inputs["reference"]
