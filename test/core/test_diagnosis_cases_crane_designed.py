"""The designed-experiment crane cases of the diagnosis benchmark (bench/cases_crane.py,
``draw_designed_case``): their first recording must really confound the pair they hand to
``cablelab excite``, or the benchmark would measure nothing.

Oracle: the MuJoCo crane of the generator (not the fitting code) recorded with the slew-only
reference; the fit's own correlation of OF[hoist] and m on that recording."""
import os
import sys

import numpy as np

from cablelab import workbench
from cablelab.diagnose.identifiability import correlations
from cablelab.fit import identify

sys.path.insert(0, os.path.join(os.path.dirname(__file__), "..", "..", "bench"))
import cases_crane  # noqa: E402


def _pair_correlation(case, path):
    cases_crane.write_bag(case, path)
    plant, desc, ds = workbench.load(path, None, dict(case.options))
    model = workbench.build_model(plant, desc, tuple(case.effects) + ("torque_sensor_offset",),
                                  fixed=case.fixed)
    names, corr = correlations(identify(model, ds))
    a, b = (names.index(p) for p in cases_crane.PAIR)
    return abs(corr[a, b])


def test_designed_case_shape():
    pair, control = cases_crane.draw_designed_case(6000), cases_crane.draw_designed_case(6003)
    assert pair.hidden == ("torque_sensor_offset",) and control.hidden == ()
    for case in (pair, control):
        assert "m" not in case.fixed                      # the payload is not weighed
        q, qd, _ = case.truth["reference"](np.linspace(0.0, 30.0, 301))
        assert np.ptp(q[:, 0]) > 0.5 and np.ptp(q[:, 1:], axis=0).max() == 0.0 and not qd[:, 1:].any()
    assert np.all(np.abs(pair.truth["offset"]) > 0) and not np.any(control.truth["offset"])
    assert set(pair.true_params["torque_sensor_offset"]) == {"OF[slew]", "OF[luff]", "OF[hoist]"}


def test_first_recording_confounds_the_pair(tmp_path):
    case = cases_crane.draw_designed_case(6000)
    case.truth["duration"] = 20.0
    assert _pair_correlation(case, tmp_path / "slew_only") > 0.98
