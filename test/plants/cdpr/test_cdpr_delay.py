"""time_delay on the CDPR: the measured tensions lag the platform motion by tau.

Oracle: bench/cases_cdpr.py (own structure matrix and tension distribution, none of the fitting
code) evaluates the whole chain reference -> wrench -> tensions at t - tau; the fit must recover
tau (sub-sample) because the CDPR ``remeasure`` hook re-forms the wrench with W at the pose the
tensions belong to. Without the hook, shifting W with the motion biases tau (the geometric term
(W(t) - W(t - tau)) t is larger than the inertial one m (a(t) - a(t - tau)) on point-to-point moves).
"""
import dataclasses
import os
import sys

import numpy as np

from cablelab import registry, workbench
from cablelab.fit import identify

sys.path.insert(0, os.path.join(os.path.dirname(__file__), "..", "..", "..", "bench"))
import cases_cdpr  # noqa: E402


def _fit_tau(tmp_path, monkeypatch=None, hook=True, tensions="dynamometer"):
    case = cases_cdpr.draw_case(13, "one")            # point-to-point moves, 200 Hz, dynamometers
    assert case.hidden == ("time_delay",) and case.family == "ptp both"
    case.options = {"tensions": tensions}
    case.truth.update(duration=20.0, noise_rel=np.full(8, 1e-5), outlier_rate=0.0)
    path = tmp_path / "cdpr_delay"
    cases_cdpr.write_bag(case, path)
    plant, desc, ds = workbench.load(path, None, dict(case.options))
    if not hook:
        monkeypatch.setitem(registry._REGISTRY, "cdpr", dataclasses.replace(plant, remeasure=None))
    model = workbench.build_model(plant, desc, case.effects + ("time_delay",), fixed=case.fixed)
    fit = identify(model, ds)
    return fit.params["tau"], fit.stderr["tau"], case.truth["tau"], ds.t[1] - ds.t[0]


def test_cdpr_delay_recovered_sub_sample_with_remeasure(tmp_path):
    tau, se, true, dt = _fit_tau(tmp_path)
    assert abs(true / dt - round(true / dt)) > 0.1             # a fractional number of samples
    assert abs(tau - true) < 0.02 * true, (tau, true)
    assert 0.0 < se < 0.02 * true


def test_cdpr_delay_biased_when_w_is_shifted_with_the_motion(tmp_path, monkeypatch):
    tau, _, true, _ = _fit_tau(tmp_path, monkeypatch, hook=False)
    assert abs(tau - true) > 0.2 * true, (tau, true)


def test_cdpr_delay_recovered_with_the_torque_balance_channels(tmp_path):
    """--tensions both: the balance channels (measured against measured, both delayed alike) keep
    their samples and rest mask under the shift; the wrench is re-formed at t - tau as above."""
    tau, se, true, dt = _fit_tau(tmp_path, tensions="both")
    assert abs(tau - true) < 0.02 * true, (tau, true)
    assert 0.0 < se < 0.02 * true
