"""Effect ``phase_effective_mass`` (spec 003_leg.md sec. 7, 003 sec. 3.4 / E9): the link rotation
adds inertia in stance, not weight. Stance ``m_s zdd = F_in + F_s - d_s zdot - m_f g``, flight
``m_f zdd = -d_f zdot - m_f g`` with m_f the weighed mass.

Flight alone only sees ``d_f / m_f``; the stance sees the inertia m_s against the weight m_f g.
With the weighed mass known, the workbench's inverse model (plants/leg/dataset.py, column
``acc_stance``) finds m_s. Data: the scipy reference (plants/leg/reference.py, solve_ivp per
phase), which shares no code with the inverse model, measured like the hardware (0.09 mm encoder,
contact switch, 1 % torque noise), 1 kHz.
"""
from __future__ import annotations

import math

import numpy as np
import pytest

from cablelab.description import load_description
from cablelab.plants.leg.hybrid import LegParams, flight_closed_form, static_deflection
from cablelab.plants.leg.reference import run_reference, sampled_trajectory
from cablelab.plants.leg.sim import simulate, write_bag
from cablelab.workbench import build_model, diagnose, identify_report, load

M_F, M_S = 1.50, 1.72          # weighed mass, stance inertia (kg): dm_f = m_f - m_s = -0.22 kg
HIDDEN = LegParams(m=M_S, m_f=M_F)
CONTROL = LegParams(m=M_F)
SCHEDULE = [(1.5, 0.30), (2.5, 0.35), (3.0, 0.30)]   # eq. 26 (T N m, P s), 4 s each
DESC = """plant: leg
gravity: 9.81
leg:
  mass: {mass}
  spring_stiffness: 605.0
  link_length: 0.15
  free_angle: 0.349066
  encoder_resolution: 9.0e-5
"""


def _record(p: LegParams, path):
    """12 s of the reference under the eq. 26 schedule, measured, written as a leg bag."""
    traj = sampled_trajectory(p, p.z_td + 0.03, 0.0, 12.0, schedule=SCHEDULE, block_s=4.0, seed=3)
    flights = [b.t - a.t for a, b in zip(traj.events[:-1], traj.events[1:])
               if a.kind == "liftoff" and b.kind == "touchdown"]
    # every transition is an edge of the sampled switch (no flight shorter than a few samples)
    assert len(flights) > 15 and min(flights) > 0.005
    rng = np.random.default_rng(7)
    traj.tau = traj.tau + 0.01 * float(np.sqrt(np.mean(traj.tau**2))) * rng.standard_normal(traj.tau.size)
    write_bag(path, traj, DESC.format(mass=M_F))
    return load(path)


@pytest.fixture(scope="module")
def hidden(tmp_path_factory):
    return _record(HIDDEN, tmp_path_factory.mktemp("phase_mass") / "hidden")


@pytest.fixture(scope="module")
def control(tmp_path_factory):
    return _record(CONTROL, tmp_path_factory.mktemp("phase_mass") / "control")


def test_stance_weight_is_the_weighed_mass():
    """Passive drop: flight by the closed form (it does not depend on m_s), rest at the static
    deflection of the weight m_f g (not m_s g), in the reference and the MuJoCo plant alike."""
    z0 = HIDDEN.z_td + 0.05
    ref = run_reference(HIDDEN, z0, 0.0, 6.0)
    td = next(e for e in ref.events if e[1] == "touchdown")
    tt = np.linspace(0.0, td[0], 400)
    z_cf, _ = flight_closed_form(tt, z0, 0.0, HIDDEN)
    t_cf = tt[np.argmin(np.abs(z_cf - HIDDEN.z_td))]
    assert td[0] == pytest.approx(t_cf, abs=2 * (tt[1] - tt[0]))
    assert static_deflection(HIDDEN) == pytest.approx(M_F * 9.81 / 605.0, rel=1e-12)
    z_rest = HIDDEN.spring_rest - M_F * 9.81 / 605.0
    z_end, _, _ = ref.sample(np.array([6.0]))
    assert z_end[0] == pytest.approx(z_rest, abs=2e-5)
    # the stance mass sets the frequency: the decaying oscillation about z_rest has sqrt(k / m_s)
    sim = simulate(HIDDEN, z0, 0.0, 6.0)
    assert sim.z[-1] == pytest.approx(z_rest, abs=2e-5)
    z_ref, _, _ = ref.sample(sim.t)
    assert np.max(np.abs(sim.z - z_ref)) < 1e-3
    st = sim.t > td[0] + 0.05
    peaks = sim.t[st][1:-1][(np.diff(sim.z[st])[:-1] > 0) & (np.diff(sim.z[st])[1:] <= 0)]
    omega_d = 2 * math.pi / float(np.median(np.diff(peaks[:4])))
    wn, zeta = math.sqrt(605.0 / M_S), HIDDEN.d_s / (2 * math.sqrt(605.0 * M_S))
    assert omega_d == pytest.approx(wn * math.sqrt(1 - zeta**2), rel=0.01)


def test_hidden_phase_mass_found_first_and_significant(hidden):
    plant, desc, ds = hidden
    model = build_model(plant, desc, ("impact_restitution",), fixed={"m": M_F})
    out = diagnose(ds, model, plant.candidates(desc), greedy_mode=True).to_json()
    first = out["ranking"][0]
    assert first["effect"] == "phase_effective_mass" and first["significant"]
    assert [s["added"] for s in out["greedy"][1:]] == ["phase_effective_mass"]
    p = out["final"]["params"]
    assert p["dm_f"] == pytest.approx(M_F - M_S, rel=0.05)
    assert p["m"] - p["dm_f"] == pytest.approx(M_S, rel=0.01)       # the stance inertia m_s
    assert out["greedy"][1]["error"] < 0.7 * out["greedy"][0]["error"]


def test_control_calls_nothing_significant(control):
    plant, desc, ds = control
    model = build_model(plant, desc, ("impact_restitution",), fixed={"m": M_F})
    out = diagnose(ds, model, plant.candidates(desc), greedy_mode=True).to_json()
    assert not any(r["significant"] for r in out["ranking"])
    assert [s["added"] for s in out["greedy"][1:]] == []


def test_mass_free_the_phase_mass_is_a_spring_preload(hidden):
    """Why the mass must be weighed: with m free, ``m_s zdd + m_f g`` in stance is
    ``m_s (zdd + g) - F_0`` with F_0 = (m_s - m_f) g, and flight fits any m (its equation is
    homogeneous in the mass): the preload model fits the phase-mass data as well, with m = m_s."""
    plant, desc, ds = hidden
    pre = identify_report(ds, build_model(plant, desc, ("impact_restitution", "spring_preload")), folds=0)
    ph = identify_report(ds, build_model(plant, desc, ("impact_restitution", "phase_effective_mass"),
                                  fixed={"m": M_F}), folds=0)
    assert pre.params["F0"]["value"] == pytest.approx((M_S - M_F) * 9.81, rel=0.05)
    assert pre.params["m"]["value"] == pytest.approx(M_S, rel=0.01)
    # the same fit up to the flight rows, whose residual (acceleration noise x mass) grows by m_s / m_f
    assert ph.quality.nrmse <= pre.quality.nrmse <= ph.quality.nrmse * M_S / M_F
