"""MuJoCo CDPR plant: real pulleys, cables that only pull, winch friction, closed loop (001)."""
import mujoco
import numpy as np
import pytest

from cablelab.description import load_description
from cablelab.plants.cdpr.geometry import cable_geometry
from cablelab.plants.cdpr.trajectory import Trajectory
from cablelab.plants.cdpr.sim import CdprSim, CdprTruth, simulate

CAROCA = "src/cablelab/cablelab/plants/cdpr/data/caroca.yaml"


@pytest.fixture(scope="module")
def desc():
    return load_description(CAROCA)


def _hold(sim, position, seconds, torque):
    for _ in range(int(seconds / sim.truth.timestep / 10)):
        sim.step(torque, 10)


def test_tendon_length_and_swivel_match_hand_formula(desc):
    """Kinematics: with the swivels at atan2 to the anchor, each tendon is the carriage run +
    r_p * wrap angle + tangent segment (the hand formula of Model II, 001 eq. 6-9)."""
    c = desc.cdpr
    sim = CdprSim(desc, CdprTruth(), np.array([0.0, 0.0, 1.0]))
    m, d = sim.model, sim.data
    run = sim.cable_total - sim.measure()["cable_length"]      # vertical run below A_i
    for p in ([0.3, -0.2, 0.8], [-1.0, 0.4, 1.3], [0.9, 0.3, 0.6]):
        g = cable_geometry(c.exit_points, c.anchor_points, np.array(p), None, 0.15)
        d.qpos[sim._free_q:sim._free_q + 3] = p
        d.qpos[sim._swivel_q] = g.swivel_angles[0]
        mujoco.mj_forward(m, d)
        A, B = c.exit_points, c.anchor_points + p
        np.testing.assert_allclose(g.swivel_angles[0], np.arctan2(B[:, 1] - A[:, 1], B[:, 0] - A[:, 0]))
        # 1e-4 m: the rim via-site sits 0.1 % of r_p above the sheave
        np.testing.assert_allclose(d.ten_length - run, g.lengths[0], atol=1e-4)


def test_free_swivel_aligns_under_tension(desc):
    """The swivel hinges are free: started 0.2 rad off, cable tension turns each sheave to
    atan2(B - A) (the rim via-site makes the aligned path the shortest)."""
    c = desc.cdpr
    p = np.array([0.4, -0.2, 1.0])
    sim = CdprSim(desc, CdprTruth(winch_coulomb=0.0, winch_viscous=0.0), p)
    sim.data.qpos[sim._swivel_q] += 0.2 * np.array([1, -1, 1, -1, 1, -1, 1, -1])
    g = cable_geometry(c.exit_points, c.anchor_points, p, None, 0.15)
    from cablelab.plants.cdpr.control import feedforward_tensions
    tau = feedforward_tensions(g, 366.0, np.zeros(3))[0] * c.drum_radius / c.gear_ratio
    _hold(sim, p, 3.0, tau)
    st = sim.truth_state()
    g = cable_geometry(c.exit_points, c.anchor_points, st["position"], None, 0.15)
    np.testing.assert_allclose(st["swivel"], g.swivel_angles[0], atol=2e-3)


def test_cables_only_pull_and_slack_is_reported(desc):
    """A motor paying out (negative torque) cannot push: while the others hold the pose (PDFF),
    its cable goes slack with tension exactly 0, never negative, and is flagged slack."""
    from cablelab.plants.cdpr.live import LiveController
    c = desc.cdpr
    p = np.array([0.0, 0.0, 1.0])
    sim = CdprSim(desc, CdprTruth(winch_coulomb=0.0), p)
    ctl = LiveController(c)
    for k in range(150):
        ms = sim.measure()
        tau = ctl.update(k * 0.01, ms["motor_angle"], ms["motor_velocity"], p)
        tau[0] = -0.5
        sim.step(tau, 10)
    st = sim.truth_state()
    assert st["tension"][0] == 0.0 and st["slack"][0]
    assert np.all(st["tension"] >= 0.0)
    assert st["slack"][1:].sum() <= 1                    # at most its antagonist goes slack too
    assert np.linalg.norm(st["position"] - p) < 0.1      # the others still hold it


def test_static_torque_is_tension_plus_friction(desc):
    """CONTRACT: at rest, effort = r/R * tension (+ friction only while moving). Holding a pose
    with the feedforward torques, the dynamometers read R/r * torque and the mass of eq. 13 is the
    simulated mass (platform + 122 kg payload)."""
    c = desc.cdpr
    p = np.array([-0.5, 0.2, 0.9])
    truth = CdprTruth(payload_mass=122.0, tension_noise=0.0, torque_noise=0.0)
    sim = CdprSim(desc, truth, p)
    g = cable_geometry(c.exit_points, c.anchor_points, p, None, 0.15)
    from cablelab.plants.cdpr.control import feedforward_tensions
    from cablelab.plants.cdpr.estimation import mass_com
    com = truth.resolved(desc).total_com
    t_ff = feedforward_tensions(g, 488.0, np.zeros(3), com=np.array([com[0], com[1], 0.0]))[0]
    _hold(sim, p, 2.0, t_ff * c.drum_radius / c.gear_ratio)
    ms = sim.measure()
    np.testing.assert_allclose(ms["tension"], t_ff, rtol=2e-3)
    st = sim.truth_state()
    g = cable_geometry(c.exit_points, c.anchor_points, st["position"], None, 0.15)
    est = mass_com(g, ms["tension"][None])
    assert abs(est.mass[0] - 488.0) < 0.5
    np.testing.assert_allclose(est.com[0], com[:2], atol=2e-3)


def test_winch_coulomb_friction_in_motor_torque(desc):
    """Reeling in at constant speed costs r/R t + F_c + F_v qdot of motor torque (001 eq. 15):
    the measured motor torques minus r/R * dynamometer tension give back F_c + F_v qdot."""
    truth = CdprTruth(winch_coulomb=0.3, winch_viscous=0.002, tension_noise=0.0, torque_noise=0.0)
    t = np.arange(0, 6.0, 0.01)
    P = np.zeros((len(t), 3))
    P[:, 2] = 0.8 + 0.1 * t                     # constant 0.1 m/s lift after the start
    V = np.zeros_like(P)
    V[:, 2] = 0.1
    run = simulate(desc, truth, controller="pdff", reference=Trajectory(t, P, V, np.zeros_like(P)))
    c = desc.cdpr
    k = c.drum_radius / c.gear_ratio
    sel = slice(300, 600)
    fric = run.motor_torque[sel] - k * run.tension[sel]
    qd = run.motor_velocity[sel]
    assert np.all(qd > 10.0)                     # every cable reels in
    np.testing.assert_allclose(np.median(fric - 0.002 * qd, axis=0), 0.3, atol=0.03)


def test_closed_loop_pd_vs_pdff_fig15(desc):
    """001 Fig. 15 on the heaviest payload (615 kg): the PD (no feedforward) sags well below the
    reference; PDFF with the live mass keeps |z error| < 5 mm; no cable goes slack."""
    truth = CdprTruth(payload_mass=249.0)
    err = {}
    for ctl in ("pd", "pdff"):
        run = simulate(desc, truth, controller=ctl, duration=30.0)
        err[ctl] = np.abs(run.true_position[:, 2] - run.ref_position[:, 2]).max()
        assert not run.slack.any()
    assert err["pdff"] < 0.005
    assert err["pd"] > 3 * err["pdff"] and err["pd"] > 0.012


def test_any_geometry_tilted_swivels(desc):
    """Another robot: CAROCA's layout at half scale, sheaves of 0.05 m on swivel axes tilted by
    ~10 deg. The MuJoCo tendons equal the Model II hand formula once each sheave is turned to its
    geometric swivel angle, and the cable tension aligns the free swivels (to 0.02 rad from 0.15 rad off:
    on a tilted axis the sheave's own weight pulls it slightly downhill, as on a real pulley)."""
    from cablelab.description import load_description
    rng = np.random.default_rng(5)
    lines = ["plant: cdpr", "cdpr:", "  drum_radius: 0.03", "  gear_ratio: 10", "  pulley_radius: 0.05",
             "  platform_mass: 200", "  cables:"]
    for cab in desc.cdpr.cables:
        ax = np.array([0.15 * rng.standard_normal(), 0.15 * rng.standard_normal(), 1.0])
        ax /= np.linalg.norm(ax)
        A, B = 0.5 * cab.exit_point, 0.5 * cab.anchor_point
        lines.append(f"    - {{exit_point: [{A[0]}, {A[1]}, {A[2]}], anchor_point: [{B[0]}, {B[1]}, {B[2]}], "
                     f"swivel_axis: [{ax[0]:.4f}, {ax[1]:.4f}, {ax[2]:.4f}]}}")
    small = load_description("\n".join(lines) + "\n")
    c = small.cdpr
    p = np.array([0.1, -0.05, 0.5])
    sim = CdprSim(small, CdprTruth(winch_coulomb=0.0, winch_viscous=0.0, platform_mass=200.0), p)
    run = sim.cable_total - sim.measure()["cable_length"]
    for q in ([0.2, 0.1, 0.4], [-0.3, 0.1, 0.6]):
        g = cable_geometry(c.exit_points, c.anchor_points, np.array(q), None, 0.05, c.swivel_axes)
        sim.data.qpos[sim._free_q:sim._free_q + 3] = q
        sim.data.qpos[sim._swivel_q] = g.swivel_angles[0]
        mujoco.mj_forward(sim.model, sim.data)
        np.testing.assert_allclose(sim.data.ten_length - run, g.lengths[0], atol=5e-5)
    # free swivels align under tension (the platform held by the feedforward torques)
    sim.reset(p)
    sim.data.qpos[sim._swivel_q] += 0.15
    from cablelab.plants.cdpr.control import feedforward_tensions
    g = cable_geometry(c.exit_points, c.anchor_points, p, None, 0.05, c.swivel_axes)
    t_ff = feedforward_tensions(g, 200.0, np.zeros(3), preload=300.0)[0]
    assert t_ff.min() > 10.0
    _hold(sim, p, 3.0, t_ff * c.drum_radius / c.gear_ratio)
    st = sim.truth_state()
    assert np.linalg.norm(st["position"] - p) < 0.02 and not st["slack"].any()
    g = cable_geometry(c.exit_points, c.anchor_points, st["position"], None, 0.05, c.swivel_axes)
    np.testing.assert_allclose(st["swivel"], g.swivel_angles[0], atol=0.02)   # from 0.15 rad off
