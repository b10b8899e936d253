"""The crane's designed delay cases (bench/cases_crane.py ``draw_delay_case``): what the first
recording hides and how slow it is, checked on the drawn case (no simulation)."""
import os
import sys

import numpy as np

sys.path.insert(0, os.path.join(os.path.dirname(__file__), "..", "..", "bench"))
import cases_crane  # noqa: E402


def test_delay_cases_hide_a_delay_in_slow_moves_inside_the_ranges():
    for seed in range(8000, 8008):
        case = cases_crane.draw_delay_case(seed)
        tr = case.truth
        if seed % 4 == 3:
            assert case.hidden == () and tr["tau"] == 0.0
        else:
            assert case.hidden == ("time_delay",) and 0.02 <= tr["tau"] <= 0.045
            assert case.true_params == {"time_delay": {"tau": tr["tau"]}}
        assert tuple(tr["pair"]) == ("tau", "I_tot") and "m" in case.fixed
        t = np.arange(0.0, tr["first_s"], 0.01)
        q, qd, qdd = tr["reference"](t)
        # a 45 ms delay moves the position by at most max|qd| * 45 ms: a few mm or mrad
        assert np.abs(qd).max(axis=0).max() * 0.045 < 0.01
        # consistent derivatives (finite differences of the reference itself)
        assert np.allclose(np.gradient(q, t, axis=0)[1:-1], qd[1:-1], atol=1e-4)
        for j, (lo, hi) in enumerate(cases_crane.LIMITS):
            assert lo <= q[:, j].min() and q[:, j].max() <= hi
