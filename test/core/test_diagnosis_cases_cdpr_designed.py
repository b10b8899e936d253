"""The designed-experiment CDPR cases of the diagnosis benchmark (bench/cases_cdpr.py,
``draw_designed_case``): their first recording must really confound the dynamometer offsets with
the payload's mass and first moments, or the benchmark would measure nothing; and the
generator's truth must carry the payload's off-centre weight.

Oracles: statics of a level platform (the cables' moment about the origin is r_G x m (a - g));
the fit's own condition number of the named parameters on the generator's first recording."""
import os
import sys

import numpy as np
import pytest

from cablelab import workbench
from cablelab.excite import condition, model_for

sys.path.insert(0, os.path.join(os.path.dirname(__file__), "..", "..", "bench"))
import cases_cdpr  # noqa: E402


def test_designed_case_shape_and_off_centre_payload():
    pair, control = cases_cdpr.draw_designed_case(7000), cases_cdpr.draw_designed_case(7003)
    assert pair.hidden == ("tension_sensor_offset",) and control.hidden == ()
    assert np.all(np.abs(pair.truth["b"]) > 0) and not np.any(control.truth["b"])
    for case in (pair, control):
        assert case.options == {"tensions": "dynamometer"}
        tr = case.truth
        m, com = tr["m"], np.asarray(tr["com"])
        assert case.true_params["centre of mass"] == pytest.approx({"mx": m * com[0], "my": m * com[1]})
        # at the first pose the cables hold m (a - g) and its moment about the origin
        t = np.array([0.0, 0.01, 0.02])
        p, v, a = tr["reference"](t)
        ten = cases_cdpr._winch_truth(tr, p, v, a, t)[2]
        w = cases_cdpr.structure_matrix(cases_cdpr.cable_directions(p, tr["r_p"])[0])[0] @ ten[0]
        weight = m * (a[0] + [0.0, 0.0, cases_cdpr.G])
        assert w[:3] == pytest.approx(weight, rel=1e-9, abs=1e-9 * m * cases_cdpr.G)
        assert w[3:] == pytest.approx(np.cross(com, weight), abs=1e-6 * m * cases_cdpr.G)


def test_first_recording_confounds_offsets_and_payload(tmp_path):
    case = cases_cdpr.draw_designed_case(7000)
    case.truth["duration"] = case.truth["first_s"]
    path = tmp_path / "sway"
    cases_cdpr.write_bag(case, path)
    plant, desc, ds = workbench.load(path, None, dict(case.options))
    owners = model_for(plant, desc, cases_cdpr.PAIR, ds)[1]
    model = workbench.build_model(plant, desc, tuple(dict.fromkeys(case.effects + owners)), fixed=case.fixed)
    assert condition(model, ds, cases_cdpr.PAIR) > 1e6
