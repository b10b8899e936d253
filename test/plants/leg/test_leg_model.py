"""Acceptance tests B1-B5 of spec 003_leg.md sec. 8: constants, passive drop, periodic hopping,
MuJoCo plant against the independent scipy reference, and the E1 frozen-length guard."""
from __future__ import annotations

import math

import numpy as np
import pytest
from scipy.signal import argrelmax

from cablelab.plants.leg.hybrid import (STANCE, LegParams, flight_apex, flight_closed_form, grf,
                                        input_force, stance_omega, stance_zeta, static_deflection)
from cablelab.plants.leg.reference import run_reference
from cablelab.plants.leg.sim import open_loop, simulate
from cablelab.plants.leg.strides import apexes

P = LegParams()
ZTD = P.z_td


def test_b1_constants():
    assert ZTD == pytest.approx(0.281908, abs=1e-6)
    assert stance_omega(P) == pytest.approx(19.757, rel=1e-3)
    assert stance_zeta(P) == pytest.approx(0.1037, rel=1e-3)
    assert static_deflection(P) == pytest.approx(25.13e-3, rel=1e-3)


def test_input_force_is_virtual_work_of_eq3():
    # F_in dz = tau dtheta with z = 2 L cos(theta): F_in = tau / (2 L sin theta) (003 eq. 2-3)
    theta = np.linspace(0.35, 1.2, 7)
    z = 2 * P.L * np.cos(theta)
    dz_dtheta = -2 * P.L * np.sin(theta)
    assert np.allclose(input_force(1.0, z, P), 1.0 / np.abs(dz_dtheta))


@pytest.fixture(scope="module")
def drop():
    return run_reference(P, ZTD + 0.05, 0.0, 3.0), simulate(P, ZTD + 0.05, 0.0, 3.0)


def test_b2_passive_drop_reference(drop):
    ref, _ = drop
    kinds = [e[1] for e in ref.events if e[1] != "apex"]
    assert kinds == ["touchdown"]  # no lift-off
    assert ref.events[0][0] == pytest.approx(0.1023, abs=5e-4)
    t = np.arange(0.0, 3.0, 1e-4)
    z, _, _ = ref.sample(t)
    peaks = (z[argrelmax(z)[0]] - ZTD)[:4]
    assert peaks * 1e3 == pytest.approx([-4.88, -14.61, -19.67, -22.29], abs=0.05)
    assert z[-1] - ZTD == pytest.approx(-25.13e-3, abs=0.2e-3)  # settling to the static deflection


def test_b2_passive_drop_mujoco(drop):
    ref, sim = drop
    assert [e.kind for e in sim.events] == ["touchdown"]
    assert sim.events[0].t == pytest.approx(0.1023, abs=5e-4)
    assert sim.events[0].t == pytest.approx(ref.events[0][0], abs=1e-4)  # leapfrog start (sim.py)
    peaks = (sim.z[argrelmax(sim.z)[0]] - ZTD)[:4]
    assert peaks * 1e3 == pytest.approx([-4.88, -14.61, -19.67, -22.29], abs=0.3)
    z_ref, _, _ = ref.sample(sim.t)
    assert np.max(np.abs(sim.z - z_ref)) < 2e-3


def test_flight_closed_form_matches_reference():
    ref = run_reference(P, ZTD + 0.01, 1.0, 0.15)
    t = np.linspace(0, 0.15, 50)
    z, zd, _ = ref.sample(t)
    zc, zdc = flight_closed_form(t, ZTD + 0.01, 1.0, P)
    assert np.max(np.abs(z - zc)) < 1e-9 and np.max(np.abs(zd - zdc)) < 1e-9
    ta, za = flight_apex(ZTD + 0.01, 1.0, P)
    (t_apex, z_apex), = ref.apexes()
    assert ta == pytest.approx(t_apex, abs=1e-7) and za == pytest.approx(z_apex, abs=1e-9)


@pytest.fixture(scope="module")
def s2():
    ref = run_reference(P, ZTD + 0.03, 0.0, 8.0, T=1.5, P=0.30)
    sim = simulate(P, ZTD + 0.03, 0.0, 8.0, open_loop(1.5, 0.30))
    return ref, sim


def test_b3_periodic_hopping(s2):
    ref, _ = s2
    ap = np.array(ref.apexes())
    assert (ap[-3:, 1] - ZTD) * 1e3 == pytest.approx([16.11] * 3, abs=0.05)
    assert np.diff(ap[-3:, 0]) == pytest.approx([0.5385] * 2, abs=0.002)
    trans = [e for e in ref.events if e[1] != "apex"]
    td = [e for e in trans if e[1] == "touchdown"][-1]
    lo = [e for e in trans if e[1] == "liftoff"][-1]
    assert abs(td[3]) == pytest.approx(0.548, abs=0.01) and td[4] == pytest.approx(0.57 * td[3])
    assert lo[3] == pytest.approx(0.511, abs=0.01) and lo[4] == pytest.approx(1.13 * lo[3])
    td_t = np.array([e[0] for e in trans if e[1] == "touchdown"])
    lo_t = np.array([e[0] for e in trans if e[1] == "liftoff"])
    stance = lo_t[-1] - td_t[td_t < lo_t[-1]][-1]
    flight = td_t[-1] - lo_t[lo_t < td_t[-1]][-1]
    assert stance == pytest.approx(0.424, abs=0.002) and flight == pytest.approx(0.115, abs=0.002)


def test_b4_mujoco_matches_reference(s2):
    ref, sim = s2
    n_ref = len([e for e in ref.events if e[1] != "apex"])
    assert len(sim.events) == n_ref == 29
    ap_sim = apexes(sim.t, sim.z, sim.phase)
    ap_ref = np.array(ref.apexes())
    ap_ref = ap_ref[ap_ref[:, 0] > sim.t[1]]  # the start (at rest) is not an interior apex
    assert len(ap_sim) == len(ap_ref)
    err = np.abs(ap_sim[:, 1] - ap_ref[:, 1])
    assert np.max(err[ap_ref[:, 0] > 1.0]) < 0.05e-3  # the period-1 cycle (spec: 0.014 mm)
    assert np.max(err) < 0.1e-3  # the first hop from rest carries the Euler free-fall lag
    z_ref, _, _ = ref.sample(sim.t)
    assert np.max(np.abs(sim.z - z_ref)) < 2e-3
    # the velocity maps of eq. 24 were applied exactly at every located event
    for e in sim.events:
        beta = P.beta_td if e.kind == "touchdown" else P.beta_lo
        assert e.zd_plus == pytest.approx(beta * e.zd_minus, rel=1e-12)


def test_b5_e1_frozen_length_guard():
    ni = P.no_impact()
    # the periodic apex of S2 (B3), then beta = 1
    ref = run_reference(ni, ZTD + 16.11e-3, 0.0, 3.0, T=1.5, P=0.30)
    lo = [e for e in ref.events if e[1] == "liftoff"]
    assert lo[0][2] == pytest.approx(0.2658, abs=5e-4)
    assert lo[0][3] < 0.0  # lift-off by F_GRF = 0 while still moving down, below z_td (E1)
    nxt = ref.events[ref.events.index(lo[0]) + 1]
    assert nxt[1] == "touchdown"
    assert nxt[2] == pytest.approx(lo[0][2], abs=1e-6)  # touch-down at the frozen length
    t = np.arange(0, ref.t_end, 1e-3)
    z, _, _ = ref.sample(t)
    assert np.nanmin(z) > ZTD - 0.1
    sim = simulate(ni, ZTD + 16.11e-3, 0.0, 3.0, open_loop(1.5, 0.30))
    slo = [e for e in sim.events if e.kind == "liftoff"]
    assert slo[0].z == pytest.approx(0.2658, abs=5e-4)
    assert sim.z.min() > ZTD - 0.1
    # the GRF is non-negative throughout stance (the F_GRF = 0 guard holds)
    st = sim.phase == STANCE
    assert grf(sim.z[st], sim.zd[st], sim.f_in[st], ni).min() > -0.5
    assert math.isfinite(sim.z[-1])


def test_encoder_reading_and_motor_angle_of_the_node_and_the_offline_measurement():
    """What the simulator node publishes per sample (:func:`quantise`, :func:`motor_angle`) is the
    offline measurement model's (:func:`measure`, no encoder offset) and the linkage's geometry:
    readings on the encoder grid within half a count, and z = 2 L cos(theta) back."""
    from cablelab.plants.leg.sim import Trajectory, measure, motor_angle, quantise

    rng = np.random.default_rng(2)
    z, res, L = rng.uniform(0.05, 0.29, 200), 9e-5, 0.15
    zq = np.array([float(quantise(x, res)) for x in z])
    assert np.all(np.abs(zq - z) <= res / 2 + 1e-15)
    assert np.allclose(zq / res, np.round(zq / res))
    n = z.size
    traj = Trajectory(np.arange(n) * 1e-3, z, np.zeros(n), np.zeros(n, int), np.zeros(n), np.zeros(n),
                      np.zeros(n))
    assert np.array_equal(measure(traj, resolution=res, seed=None).z_meas, zq)
    assert np.allclose(2 * L * np.cos(motor_angle(zq, L)), zq)
    assert quantise(0.1234567, 0.0) == 0.1234567
