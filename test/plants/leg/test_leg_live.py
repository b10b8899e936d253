"""Acceptance tests B8 (live hop estimator) and B9 (apex-height controller) of spec 003_leg.md
sec. 8, on the MuJoCo plant with the hardware measurement model (0.09 mm encoder)."""
from __future__ import annotations

import math

import numpy as np
import pytest

from cablelab.plants.leg.control import ApexController, next_apex
from cablelab.plants.leg.estimator import HopEstimator, estimate_series
from cablelab.plants.leg.hybrid import STANCE, LegParams, flight_apex, grf
from cablelab.plants.leg.sim import LegSim, open_loop, simulate
from cablelab.plants.leg.strides import apexes

P = LegParams()


@pytest.fixture(scope="module")
def s2():
    return simulate(P, P.z_td + 0.03, 0.0, 8.0, open_loop(1.5, 0.30))


@pytest.mark.parametrize("source", ["contact", "height"])
def test_b8_estimator_on_s2(s2, source):
    tr = s2
    out = estimate_series(tr.t, tr.z_meas, tr.contact if source == "contact" else None, tr.tau, P)
    ev = tr.event_times()
    near = np.min(np.abs(tr.t[:, None] - ev[None, :]), axis=1) <= 2e-3 + 1e-9
    assert np.all(out["phase"][~near] == tr.phase[~near])
    assert out["estimator"].used_height == (source == "height")
    truth = apexes(tr.t, tr.z, tr.phase)  # from the noiseless simulated height
    est = out["apex"]
    assert len(est) == len(truth) == 14
    assert np.max(np.abs(est[:, 1] - truth[:, 1])) < 0.2e-3
    assert np.max(np.abs(est[:, 0] - truth[:, 0])) < 2e-3
    # GRF estimate (eq. 25 on the filtered velocity) follows the truth in mid-stance
    mid = (tr.phase == STANCE) & ~(np.min(np.abs(tr.t[:, None] - ev[None, :]), axis=1) < 0.05)
    assert np.median(np.abs(out["grf"][mid] - tr.grf[mid])) < 1.0  # N, of ~15-30 N peaks
    assert out["estimator"].flips == 0


def test_estimator_survives_dropouts_and_counts_them():
    est = HopEstimator(P)
    e = est.step(0.0, P.z_td + 0.01, 0.0)
    e = est.step(0.001, math.nan, 0.0)
    assert est.dropouts == 1 and math.isfinite(e.z)
    e = est.step(0.002, P.z_td + 0.0099, 0.0)
    assert math.isfinite(e.zd)


def test_next_apex_model_matches_closed_form_without_input():
    # T = 0 and beta = 1, d = 0: the stride from an apex returns to the same height (energy)
    p = P.replace(d_s=0.0, d_f=0.0, beta_td=1.0, beta_lo=1.0)
    h = next_apex(p, P.z_td + 0.02, 0.0, 0.3)
    assert h == pytest.approx(P.z_td + 0.02, abs=0.1e-3)
    # any dissipation lowers the next apex (T = 0)
    assert next_apex(P.replace(d_s=0.0, beta_td=1.0, beta_lo=1.0), P.z_td + 0.02, 0.0, 0.3) < P.z_td + 0.0199
    # and the flight part alone follows the closed form: from z_td at 0.5 m/s up
    t_a, h_a = flight_apex(P.z_td, 0.5, P)
    assert h_a < P.z_td + 0.5**2 / (2 * 9.81) and t_a < 0.5 / 9.81


def _closed_loop(mass_scale: float, hops: int, res: float = 9e-5):
    truth = P.replace(m=P.m * mass_scale)
    sim = LegSim(truth, P.z_td + 0.016, 0.0)
    est = HopEstimator(P)
    ctl = ApexController(P, P.z_td + 0.016, T=1.0)
    hs = []
    while len(hs) < hops and sim.t < 30.0:
        e = est.step(sim.t, round(sim.z / res) * res, float(sim.phase))
        if e.new_apex:
            hs.append(e.apex_height)
            ctl.on_apex(e.apex_height)
        sim.step(ctl.torque(sim.t, e.phase))
    # the true apexes of the simulated body (not the estimate) are what is judged
    return np.array(hs) - ctl.h_des, ctl


def test_b9_apex_controller_nominal():
    err, ctl = _closed_loop(1.0, 12)
    assert abs(err[0]) > 5e-3  # starts far (T = 1.0 N m)
    assert np.all(np.abs(err[9:]) < 1e-3)  # within 1 mm within 10 hops, and stays
    assert 0.0 <= ctl.T <= ctl.T_max


@pytest.mark.parametrize("scale", [0.9, 1.1])
def test_b9_apex_controller_mass_error(scale):
    err, _ = _closed_loop(scale, 22)
    assert np.all(np.abs(err[19:]) < 1e-3)


def test_controller_holds_on_nan_apex():
    ctl = ApexController(P, P.z_td + 0.016, T=1.2)
    assert ctl.on_apex(math.nan) == 1.2
    assert ctl.torque(0.0, 0) == 0.0
    assert ctl.torque(0.01, STANCE) == 0.0  # touch-down: eq. 26 restarts at sin(0)
    assert ctl.torque(0.01 + 0.075, STANCE) == pytest.approx(1.2)  # quarter period P / 4


def test_grf_zero_at_rest_equilibrium():
    z_eq = P.spring_rest - P.m * P.g / P.k
    assert grf(z_eq, 0.0, 0.0, P) == pytest.approx(P.m * P.g)


def test_controller_step_takes_each_apex_of_the_estimate_stream_once():
    """The controller node's per-estimate step: the hop estimate repeats the last apex until the
    next one; T is updated once per apex (oracle: on_apex called once per apex), not at NaN
    apex times, and the torque is the law's for the phase."""
    h_des = P.z_td + 0.016
    ctl, ref = ApexController(P, h_des, T=1.2), ApexController(P, h_des, T=1.2)
    for k in range(5):                                   # five estimates, one apex at t = 0.5
        assert ctl.step(0.5 + 0.001 * k, 0, P.z_td + 0.010, 0.5) == 0.0
    assert ctl.T == ref.on_apex(P.z_td + 0.010) != 1.2
    ctl.step(0.9, 0, P.z_td + 0.020, math.nan)          # no apex yet
    assert ctl.T == ref.T
    ctl.step(1.0, 0, P.z_td + 0.020, 1.0)               # the next apex
    assert ctl.T == ref.on_apex(P.z_td + 0.020)
    assert ctl.step(1.1, STANCE, P.z_td + 0.020, 1.0) == ref.torque(1.1, STANCE)
    assert ctl.step(1.1 + ctl.P / 4, STANCE, P.z_td + 0.020, 1.0) == pytest.approx(ctl.T)
