"""Crane parameter accuracy on realistic recordings (bench/cases_crane.py): fixed-seed
cases of the benchmark generator (MuJoCo crane with smooth friction, quantized encoders, AR(1)
effort noise with outliers, rests) through bag -> cablelab.workbench.load -> diagnose --greedy.

* Torque-sensor offsets with a weighed calibration payload (m known, as the generator now records
  every case): the hoist force m (g cos.. - d_ddot) + offset is nearly collinear with m at small
  hoist accelerations, and m carries into the luff gravity torque; with m free the same record
  gives OF[luff], OF[hoist] 40 % off and the diagnosis flags them as confounded with m.
* Base tilt as two angles (tilt_x, tilt_y) scaled by the described masses, also on a nearly
  balanced boom (boom-side moment K ~ 0, where only the payload's swing carries the tilt: on the
  30 s record the quoted standard errors are 7-9 % of the angles, so that case is held to 8 %
  and to the 3-stderr coverage). The model is exact in the angles (the vertical gravity's
  cos|tilt| included), so no torque-sensor offset is added beside the tilt.
Quoted standard errors must cover the truth (|error| < 3 stderr per parameter).
"""
import os
import sys

import numpy as np
import pytest

from cablelab import workbench

sys.path.insert(0, os.path.join(os.path.dirname(__file__), "..", "..", "bench"))
import cases_crane  # noqa: E402
from cases_common import rel_param_error  # noqa: E402


def _run(case, tmp_path, fixed=None):
    path = tmp_path / f"crane_{case.seed}"
    if not path.exists():
        cases_crane.write_bag(case, path)
    plant, desc, ds = workbench.load(path, None, dict(case.options))
    model = workbench.build_model(plant, desc, case.effects, fixed=case.fixed if fixed is None else fixed)
    return workbench.diagnose(ds, model, plant.candidates(desc), greedy_mode=True).to_json()


def _confounded(out, effect):
    row = next(r for r in out["ranking"] if r["effect"] == effect)
    return (row.get("identifiability") or {}).get("confounded") or []


def _assert_params(out, case, rel):
    (hidden,) = case.hidden
    first = out["ranking"][0]
    assert first["effect"] == hidden and first["significant"], out["ranking"][:2]
    assert [g["added"] for g in out["greedy"][1:]] == [hidden]
    fit, se = out["final"]["params"], out["final"]["stderr"]
    true = case.true_params[hidden]
    assert rel_param_error(fit, true) < rel, {k: (v, fit[k]) for k, v in true.items()}
    for k, v in true.items():   # the quoted uncertainty covers the truth
        assert abs(fit[k] - v) < 3 * se[k], (k, fit[k], v, se[k])


def test_crane_offsets_with_a_weighed_payload(tmp_path):
    case = cases_crane.draw_case(38, "one")
    case.truth.update(duration=30.0)
    assert case.hidden == ("torque_sensor_offset",) and not case.velocity_recorded
    assert case.fixed["m"] == case.truth["payload_mass"]
    out = _run(case, tmp_path)
    _assert_params(out, case, rel=0.02)
    assert not _confounded(out, "torque_sensor_offset")
    # the same record with the payload mass free: the offsets are confounded with m, and says so
    free_m = {k: v for k, v in case.fixed.items() if k != "m"}
    loose = _run(case, tmp_path, fixed=free_m)
    assert {c["with"] for c in _confounded(loose, "torque_sensor_offset")} == {"m"}
    assert rel_param_error(loose["final"]["params"], case.true_params["torque_sensor_offset"]) > 0.1


@pytest.mark.parametrize("seed", [1, 6])
def test_crane_base_tilt_angles(tmp_path, seed):
    case = cases_crane.draw_case(seed, "one")
    case.truth.update(duration=30.0)
    assert case.hidden == ("base_tilt",)
    tr = case.truth
    K = tr["boom_length"] * (tr["payload_mass"] + tr["boom_mass"] / 2) \
        - tr["counterbalance_distance"] * tr["counterbalance_mass"]
    assert (abs(K) > 0.5) if seed == 1 else (abs(K) < 0.05)     # seed 6: a nearly balanced boom
    out = _run(case, tmp_path)
    _assert_params(out, case, rel=0.02 if seed == 1 else 0.08)
    tilt = np.hypot(*[case.true_params["base_tilt"][k] for k in ("tilt_x", "tilt_y")])
    assert np.radians(1.0) < tilt < np.radians(4.5)
