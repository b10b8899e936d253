"""The CDPR's designed delay cases (bench/cases_cdpr_delay.py ``draw_delay_case``): what the first
recording hides, that its slow sines keep the delay below the dynamometers' noise (the
generator's own visibility: the delay's change of the wrench in noise rms), and that the
benchmark finds the family."""
import os
import sys

import numpy as np

sys.path.insert(0, os.path.join(os.path.dirname(__file__), "..", "..", "bench"))
import bench_diagnosis  # noqa: E402
import cases_cdpr  # noqa: E402
import cases_cdpr_delay  # noqa: E402


def test_delay_cases_hide_a_delay_the_slow_first_recording_does_not_show():
    for seed in range(9000, 9004):
        case = cases_cdpr_delay.draw_delay_case(seed)
        tr = case.truth
        assert case.options == {"tensions": "dynamometer"} and "r_p" in case.fixed
        assert tuple(tr["pair"]) == ("tau", "m_a") and "platform_inertia" in case.effects
        t = np.arange(0.0, tr["first_s"], 0.01)
        q, qd, qdd = tr["reference"](t)
        assert np.allclose(np.gradient(q, t, axis=0)[1:-1], qd[1:-1], atol=1e-4)
        for j, (lo, hi) in enumerate(cases_cdpr.LIMITS):
            assert lo <= q[:, j].min() and q[:, j].max() <= hi
        if seed % 4 == 3:
            assert case.hidden == () and tr["tau"] == 0.0
            continue
        assert case.hidden == ("time_delay",) and 0.01 <= tr["tau"] <= 0.03
        assert case.true_params == {"time_delay": {"tau": tr["tau"]}}
        tr["duration"] = tr["first_s"]
        assert 0.0 < cases_cdpr.delay_visibility(case) < 0.5


def test_benchmark_draws_the_family_from_its_module():
    plant, draw, module = bench_diagnosis.DESIGNED_DRAW["cdpr_delay"]
    assert (plant, draw, module) == ("cdpr", "draw_delay_case", "cases_cdpr_delay")
    assert bench_diagnosis.DESIGNED_SEEDS["cdpr_delay"] == 9000
