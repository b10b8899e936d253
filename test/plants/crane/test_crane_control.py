"""Crane PD + gravity compensation + acceleration feedforward (002 sec. 5.3.1) vs MuJoCo."""
import numpy as np

import mujoco

from cablelab.plants.crane.control import LIVE_GAINS, Gains, control_law, hold_command, joint_command, sim_drive
from cablelab.plants.crane.model import CraneParams
from cablelab.plants.crane.mjcf import build_mjcf
from cablelab.plants.crane.sim import CraneSim, CraneTruth, contract_to_qpos, simulate

P = CraneParams()


def test_feedforward_equals_mujoco_inverse_dynamics_at_zero_velocity():
    """With q = q_ref, qd = qd_ref = 0 the law is G_a(q) + M_aa(q) qdd_ref: MuJoCo's mj_inverse for
    that acceleration with the swing held (swing accelerations 0) gives the same actuated efforts."""
    model = build_mjcf(CraneTruth(params=P))
    data = mujoco.MjData(model)
    rng = np.random.default_rng(5)
    for _ in range(20):
        q5 = np.array([rng.uniform(-3, 3), rng.uniform(-0.8, 1.2), rng.uniform(0.2, 1.5), 0.0, 0.0])
        a = rng.normal(size=3)
        data.qpos[:] = contract_to_qpos(q5)[0]
        data.qvel[:] = 0.0
        # swing held in the slewing frame while luffing: psi_ddot = -beta_ddot (sim gimbal)
        data.qacc[:] = [a[0], a[1], -a[1], 0.0, a[2]]
        mujoco.mj_inverse(model, data)
        tau = control_law(q5[None, :3], np.zeros((1, 3)), q5[None, :3], np.zeros((1, 3)), a[None], P)[0]
        f = data.qfrc_inverse
        # contract luff torque (swing fixed in the slewing frame) = f_beta - f_psi, since
        # d theta / d beta = d theta / d psi for the gimbal (tau_mujoco = J^T tau_contract)
        np.testing.assert_allclose(tau, [f[0], f[1] - f[2], f[4]], atol=1e-9)


def test_hold_command_holds_the_crane_still():
    q = np.array([[0.3, 0.6, 0.8]])
    u = hold_command(q, np.zeros((1, 3)), P)
    model = build_mjcf(CraneTruth(params=P))
    data = mujoco.MjData(model)
    data.qpos[:] = contract_to_qpos([0.3, 0.6, 0.8, 0.0, 0.0])[0]
    data.ctrl[:] = u[0]
    mujoco.mj_forward(model, data)
    assert np.abs(data.qacc).max() < 1e-9


def test_sim_drive_applies_answers_and_fresh_commands_else_holds_against_mujoco_gravity():
    """The simulator's drive choice: an answer (lock-step) or a fresh command in real time is
    applied as given; missing, stale, or unanswered in lock-step, the drives hold: at rest that
    is MuJoCo's gravity load on the actuated joints (mj_inverse with zero acceleration, swing
    hanging), with damping opposing the joint rates."""
    model = build_mjcf(CraneTruth(params=P))
    data = mujoco.MjData(model)
    q = np.array([0.4, 0.6, 0.9, 0.0, 0.0])
    u = np.array([1.0, -2.0, 3.0])
    for answered, fresh, lockstep in [(True, False, True), (False, True, False)]:
        got, held = sim_drive(u, q, np.zeros(5), P, answered=answered, fresh=fresh, lockstep=lockstep)
        assert got is u and not held
    data.qpos[:] = contract_to_qpos(q)[0]
    data.qvel[:] = 0.0
    data.qacc[:] = 0.0
    mujoco.mj_inverse(model, data)
    f = data.qfrc_inverse
    gravity = np.array([f[0], f[1] - f[2], f[4]])     # contract luff = f_beta - f_psi (swing held)
    for args in [(None, True, False), (u, False, False), (u, True, True)]:
        got, held = sim_drive(args[0], q, np.zeros(5), P, answered=False, fresh=args[1], lockstep=args[2])
        assert held
        np.testing.assert_allclose(got, gravity, rtol=1e-6, atol=1e-6)
    qd = np.array([0.5, -0.3, 0.2, 0.0, 0.0])
    got, held = sim_drive(None, q, qd, P, answered=False, fresh=False, lockstep=False)
    np.testing.assert_allclose(got - gravity, -np.asarray(LIVE_GAINS.kd) * qd[:3], rtol=1e-6, atol=1e-6)


def test_simulator_period_holds_the_crane_until_an_answer_and_counts_the_holds():
    """``CraneSim.drive`` (one period of the simulator node): with no command the drives keep
    the crane where it is (luff within 1 mrad after 0.5 s: MuJoCo's gravity is held) and each
    period is counted as held; an answer is applied as given (the MuJoCo controls)."""
    sim = CraneSim(CraneTruth(params=P), (0.0, 0.5, 0.6))
    for _ in range(50):
        assert sim.drive(None, 0.01, answered=False, fresh=False, lockstep=True)
    _, q, _ = sim.state()
    assert abs(q[1] - 0.5) < 1e-3 and sim.held == 50
    u = np.array([0.5, -1.0, 2.0])
    assert not sim.drive(u, 0.01, answered=True, fresh=False, lockstep=True)
    np.testing.assert_array_equal(sim.data.ctrl, u)
    assert sim.held == 50


def test_joint_command_at_its_reference_or_stale_is_mujocos_gravity_load():
    """The controller node's command for one state: at rest on its reference (no acceleration)
    and with a stale reference (hold) alike it is MuJoCo's gravity load on the actuated joints;
    a NaN or missing rate counts as zero; a position error pushes toward the reference."""
    model = build_mjcf(CraneTruth(params=P))
    data = mujoco.MjData(model)
    q5 = np.array([-0.7, 0.4, 1.1, 0.0, 0.0])
    data.qpos[:] = contract_to_qpos(q5)[0]
    data.qvel[:] = data.qacc[:] = 0.0
    mujoco.mj_inverse(model, data)
    f = data.qfrc_inverse
    gravity = np.array([f[0], f[1] - f[2], f[4]])
    q, z = q5[:3], np.zeros(3)
    for qd, ref in [(z, (q, z, z)), (np.full(3, np.nan), None), (None, (q, z, z))]:
        np.testing.assert_allclose(joint_command(q, qd, ref, P), gravity, rtol=1e-6, atol=1e-6)
    u = joint_command(q, z, (q + 0.1, z, z), P, Gains())
    np.testing.assert_allclose(u - gravity, 0.1 * np.asarray(Gains().kp), rtol=1e-6)


def test_feedforward_reduces_tracking_error():
    """002 sec. 5.3.1: PD with gravity compensation and feedforward tracks far better than PD."""
    truth = CraneTruth(params=P)
    err = {}
    for ff in (True, False):
        r = simulate(truth, 20.0, feedforward=ff, decimate=10)
        err[ff] = np.sqrt(np.mean((r.q[:, :3] - r.q_ref) ** 2, axis=0))
    assert err[True][1] < 0.2 * err[False][1] and err[True][2] < 0.2 * err[False][2], err
    assert err[True][0] < err[False][0], err
    # PD alone sags under gravity: the luff error is the gravity torque over kp
    assert err[False][1] > 0.05


def test_control_law_is_vectorised_and_pd_signs():
    g = Gains()
    n = 7
    q = np.zeros((n, 3))
    tau = control_law(q, q, q + 0.1, q, q, P, g, feedforward=False)
    np.testing.assert_allclose(tau, np.tile(0.1 * np.array(g.kp), (n, 1)))


def test_controller_node_loads_neither_the_simulator_nor_mujoco():
    """The live controller evaluates the multi-sine excitation from the ROS-free reference module:
    importing its node module (fresh interpreter) loads neither ``crane/sim.py`` nor MuJoCo, and
    the reference the simulator uses is that same function."""
    import subprocess
    import sys

    code = ("import sys, cablelab.plants.crane.nodes.controller; "
            "print(sorted(m for m in ('mujoco', 'cablelab.plants.crane.sim') if m in sys.modules))")
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, check=True).stdout
    assert out.strip() == "[]"
    from cablelab.plants.crane import reference, sim

    assert sim.reference_trajectory is reference.reference_trajectory
    t = np.linspace(0.0, 10.0, 2001)
    q, qd, qdd = reference.reference_trajectory(t, seed=3)
    assert np.allclose(q[0], (0.0, 0.5, 0.6))                      # starts at q0 (fade-in)
    # the returned rates are the derivatives of the returned positions (central differences)
    dt = t[1] - t[0]
    assert np.allclose(np.gradient(q, dt, axis=0)[1:-1], qd[1:-1], atol=2e-3)
    assert np.allclose(np.gradient(qd, dt, axis=0)[1:-1], qdd[1:-1], atol=2e-2)
