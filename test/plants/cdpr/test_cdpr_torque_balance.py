"""CDPR ``--tensions both``: the per-winch torque balance ``(R/r) tau_i - d_i``.

With the dynamometers alone the eight tension offsets reach the six wrench channels through W,
whose two-dimensional null space (internal forces) is invisible at each pose; the balance of the
motor torque against the dynamometer reading (001 eq. 15: tau_i = (r/R) t_i + winch friction)
cancels the unknown tension and leaves ``(R/r) (F_c sign(qdot) + F_v qdot) - b_i`` per winch.

Oracle: bench/cases_cdpr.py (own structure matrix, tension distribution, smooth tanh winch friction,
none of the fitting code): the balance channels against its truth in closed form, and fixed-seed
benchmark cases through the real path (bag -> workbench.load -> diagnose --greedy).
"""
import os
import sys

import numpy as np
import pytest

from cablelab import workbench
from cablelab.errors import CablelabError
from cablelab.fit import identify

sys.path.insert(0, os.path.join(os.path.dirname(__file__), "..", "..", "..", "bench"))
import cases_cdpr  # noqa: E402
from cases_common import rel_param_error  # noqa: E402


def _quiet_case(seed=3009):
    """A friction case (Coulomb + viscous) with dynamometer offsets too and almost no noise."""
    case = cases_cdpr.draw_case(seed)
    assert set(case.hidden) == {"winch_coulomb_friction", "winch_viscous_friction"}
    t_mean = case.truth["m"] * cases_cdpr.G / 8 / 0.6
    case.truth.update(duration=20.0, noise_rel=np.full(8, 1e-7), outlier_rate=0.0,
                      b=np.linspace(-0.08, 0.08, 8) * t_mean)
    return case


def test_balance_channels_are_friction_minus_offset_in_closed_form(tmp_path):
    case = _quiet_case()
    rec = cases_cdpr.write_bag(case, tmp_path / "bal")
    _, _, ds = workbench.load(tmp_path / "bal", None, {"tensions": "both"})
    tr = case.truth
    assert ds.channels[6:] == tuple(f"balance_{i}" for i in range(1, 9)) and ds.units[6:] == ("N",) * 8
    scale = cases_cdpr.GEAR / cases_cdpr.DRUM
    truth = scale * (tr["Fc"] * np.tanh(rec["omega"] / tr["eps"]) + tr["Fv"] * rec["omega"]) - tr["b"]
    mask = ds.signals["balance_mask"].astype(bool)
    assert ds.t.size == truth.shape[0]
    # moving winches: the balance is the truth's friction minus offset (noise 1e-7 of a tension)
    np.testing.assert_allclose(ds.y[:, 6:][mask], truth[mask], atol=1e-3 * np.abs(tr["b"]).max())
    # stopped winches (the platform at rest: every winch) are left out of the balance, and the
    # samples with a winch at rest out of the fit (whole-sample zero-speed exclusion, as with the
    # dynamometers alone: static poses confound the sheave radius with the mass in the wrench)
    rest = np.all(np.abs(rec["omega"]) < 1e-9, axis=1)
    assert rest.mean() > 0.15 and not mask[rest].any() and np.all(ds.y[:, 6:][~mask] == 0.0)
    assert not ds.valid[rest].any() and ds.valid[mask.all(axis=1)].mean() > 0.9


def test_offsets_and_friction_identified_per_winch_from_the_balance(tmp_path):
    case = _quiet_case()
    cases_cdpr.write_bag(case, tmp_path / "bal")
    effects = case.effects + ("winch_coulomb_friction", "winch_viscous_friction", "tension_sensor_offset")
    plant, desc, ds = workbench.load(tmp_path / "bal", None, {"tensions": "both"})
    fit = identify(workbench.build_model(plant, desc, effects, fixed=case.fixed), ds)
    tr, names = case.truth, cases_cdpr.WINCHES
    b = np.array([fit.params[f"b[{w}]"] for w in names])
    fc = np.array([fit.params[f"Fc[{w}]"] for w in names])
    fv = np.array([fit.params[f"Fv[{w}]"] for w in names])
    np.testing.assert_allclose(b, tr["b"], atol=2e-3 * np.abs(tr["b"]).max())
    # smooth tanh truth against the sign model outside the zero-speed zone: within 1 %
    np.testing.assert_allclose(fc, tr["Fc"], rtol=0.01)
    np.testing.assert_allclose(fv, tr["Fv"], rtol=0.01)
    assert fit.units["Fc[winch_1]"] == "N m" and fit.units["b[winch_1]"] == "N"


def test_hidden_offsets_recovered_with_both_not_with_the_wrench_alone(tmp_path):
    """Benchmark case 3018 (100 Hz chirp, offsets 3-10 % of the mean tension, 0.3-3 % coloured
    noise), 30 s: the torque balance recovers the offsets within 3 %; the wrench alone misses
    their internal-force component (the old behaviour, 40 % on the full case)."""
    case = cases_cdpr.draw_case(3018)
    assert case.hidden == ("tension_sensor_offset",) and case.options == {"tensions": "both"}
    case.truth.update(duration=30.0)
    path = tmp_path / "off"
    cases_cdpr.write_bag(case, path)
    plant, desc, ds = workbench.load(path, None, {"tensions": "both"})
    model = workbench.build_model(plant, desc, case.effects, fixed=case.fixed)
    out = workbench.diagnose(ds, model, plant.candidates(desc), greedy_mode=True).to_json()
    assert out["ranking"][0]["effect"] == "tension_sensor_offset" and out["ranking"][0]["significant"]
    assert [g["added"] for g in out["greedy"][1:]] == ["tension_sensor_offset"]
    err_both = rel_param_error(out["final"]["params"], case.true_params["tension_sensor_offset"])
    assert err_both < 0.03, err_both
    _, _, dsd = workbench.load(path, None, {"tensions": "dynamometer"})
    fit = identify(model.with_effect("tension_sensor_offset"), dsd)
    err_dyn = rel_param_error(fit.params, case.true_params["tension_sensor_offset"])
    assert err_dyn > 3 * err_both, (err_dyn, err_both)


def test_both_needs_the_motor_torques(tmp_path):
    case = cases_cdpr.draw_case(3002)
    rec = cases_cdpr.simulate(case)
    rec["motor"][:] = np.nan
    cases_cdpr.write_bag(case, tmp_path / "nomotor", rec)
    with pytest.raises(CablelabError, match="--tensions both.*no motor torques"):
        workbench.load(tmp_path / "nomotor", None, {"tensions": "both"})


def test_motor_tension_friction_goes_through_the_model_ii_matrix(tmp_path):
    """--tensions motor, noise-free benchmark case 3014 (Coulomb winch friction, described sheaves):
    the friction acts on the cables, so it reaches the wrench through W_II = W_I + r_p S like the
    tensions do. With the Model I matrix (the old columns) F_c came out 6 % off on exact data."""
    case = cases_cdpr.draw_case(3014)
    assert case.hidden == ("winch_coulomb_friction",) and "r_p" in case.fixed
    case.truth.update(duration=20.0, noise_rel=np.full(8, 1e-7), outlier_rate=0.0)
    cases_cdpr.write_bag(case, tmp_path / "motor")
    plant, desc, ds = workbench.load(tmp_path / "motor", None, {"tensions": "motor"})
    model = workbench.build_model(plant, desc, case.effects + ("winch_coulomb_friction",), fixed=case.fixed)
    fit = identify(model, ds)
    assert rel_param_error(fit.params, case.true_params["winch_coulomb_friction"]) < 0.005
