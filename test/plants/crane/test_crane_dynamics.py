"""Crane dynamics: generated regressor vs 002's printed energies, MuJoCo inverse dynamics, simulation."""
import numpy as np
import sympy as sp

import mujoco

from cablelab.plants.crane import symbolic as crane_symbolic
from cablelab.plants.crane.model import CraneParams, inverse_dynamics, mass_matrix, gravity_vector, regressor
from cablelab.plants.crane.mjcf import build_mjcf
from cablelab.plants.crane.sim import CraneTruth, simulate

PARAMS = CraneParams(boom_length=1.2, payload_mass=0.7, boom_mass=1.3, counterbalance_mass=2.1,
                     counterbalance_distance=0.35, slew_inertia=0.08, luff_inertia=0.03, gravity=9.81)


def test_generated_module_is_up_to_date():
    with open(crane_symbolic.TARGET, encoding="utf-8") as fh:
        committed = fh.read()
    assert crane_symbolic.generate_source() == committed


def test_derived_energies_equal_002_eq_A3_A4():
    """The energies built from the contract kinematics equal 002 eq. A.3-A.4 as printed."""
    _, _, _, g, _, en = crane_symbolic.derive()
    t = en["t"]
    al, be, d, t1, t2 = en["funcs"]
    I_tot, I_b, lb, lc, m, mb, mc = en["params"]
    ad, bd, dd, t1d, t2d = (f.diff(t) for f in (al, be, d, t1, t2))
    C, S = sp.cos, sp.sin
    T_A3 = (m * dd**2 / 2 + I_tot * ad**2 / 2 + I_b * bd**2 / 2 + m * d**2 * ad**2 / 2 + m * d**2 * t2d**2 / 2
            + lb**2 * m * bd**2 / 2 + lb**2 * mb * bd**2 / 8 + lc**2 * mc * bd**2 / 2
            + lb**2 * m * C(be)**2 * ad**2 / 2 + lb**2 * mb * C(be)**2 * ad**2 / 8 + lc**2 * mc * C(be)**2 * ad**2 / 2
            + m * C(t2)**2 * d**2 * t1d**2 / 2 - m * S(t1) * d**2 * ad * t2d
            - m * C(t1)**2 * C(t2)**2 * d**2 * ad**2 / 2 - lb * m * S(be) * S(t2) * bd * dd
            + lb * m * C(be) * S(t2) * d * ad**2 - lb * m * S(be) * C(t2) * d * bd * t2d
            + m * C(t1) * C(t2) * S(t2) * d**2 * ad * t1d
            - lb * m * C(be) * C(t1) * C(t2) * bd * dd + lb * m * C(be) * C(t2) * S(t1) * ad * dd
            + lb * m * C(be) * C(t1) * C(t2) * d * ad * t1d
            + lb * m * C(be) * C(t2) * S(t1) * d * bd * t1d + lb * m * C(be) * C(t1) * S(t2) * d * bd * t2d
            + lb * m * S(be) * C(t2) * S(t1) * d * ad * bd
            - lb * m * C(be) * S(t1) * S(t2) * d * ad * t2d)
    V_A4 = g * lb * m * S(be) + g * lb * mb * S(be) / 2 - g * lc * mc * S(be) - g * m * C(t1) * C(t2) * d
    # compare numerically at random points (exact symbolic simplification is slow)
    syms = [al, be, d, t1, t2, ad, bd, dd, t1d, t2d, I_tot, I_b, lb, lc, m, mb, mc, g]
    diff_T = sp.lambdify(syms, en["T"] - T_A3, "numpy")
    diff_V = sp.lambdify(syms, en["V"] - V_A4, "numpy")
    rng = np.random.default_rng(3)
    x = rng.uniform(-2, 2, (len(syms), 200))
    assert np.abs(diff_T(*x)).max() < 1e-12
    assert np.abs(diff_V(*x)).max() < 1e-12


def _mujoco_to_contract_map():
    """Independent (sympy) map of the MuJoCo gimbal coordinates to contract coordinates.

    Returns lambdified h(x), J(x), Jdot_v(x, v) for x = qpos [alpha, beta, psi, phi, d].
    """
    x = sp.symbols("alpha beta psi phi d")
    v = sp.symbols("va vb vpsi vphi vd")
    al, be, psi, phi, d = x
    gam = be + psi
    # rope direction in the slewing frame from the MuJoCo tree: R_{-y}(beta+psi) R_x(phi) [0,0,-1]
    ry = sp.Matrix([[sp.cos(gam), 0, -sp.sin(gam)], [0, 1, 0], [sp.sin(gam), 0, sp.cos(gam)]])  # about -y
    rx = sp.Matrix([[1, 0, 0], [0, sp.cos(phi), -sp.sin(phi)], [0, sp.sin(phi), sp.cos(phi)]])
    u = ry * rx * sp.Matrix([0, 0, -1])
    th2 = sp.asin(u[0])
    th1 = sp.atan2(u[1], -u[2])
    h = sp.Matrix([al, be, d, th1, th2])
    J = h.jacobian(x)
    Jdv = (J * sp.Matrix(v)).jacobian(x) * sp.Matrix(v)
    return (sp.lambdify([x], h, "numpy"), sp.lambdify([x], J, "numpy"), sp.lambdify([x, v], Jdv, "numpy"))


def test_mujoco_inverse_dynamics_equals_symbolic_eom():
    """mj_inverse of the MuJoCo crane == Y(q, qd, qdd) pi from 002's energies, over random states."""
    model = build_mjcf(CraneTruth(params=PARAMS))
    data = mujoco.MjData(model)
    h, J, Jdv = _mujoco_to_contract_map()
    rng = np.random.default_rng(7)
    worst = 0.0
    scale = 0.0
    for _ in range(100):
        qpos = np.array([rng.uniform(-3, 3), rng.uniform(-1.2, 1.2), rng.uniform(-0.8, 0.8),
                         rng.uniform(-0.8, 0.8), rng.uniform(0.2, 2.0)])
        qvel = rng.normal(size=5)
        qacc = rng.normal(size=5) * 2
        data.qpos[:], data.qvel[:], data.qacc[:] = qpos, qvel, qacc
        mujoco.mj_inverse(model, data)
        tau_mj = data.qfrc_inverse.copy()
        Jx = np.asarray(J(qpos), float)
        q = np.asarray(h(qpos), float).ravel()
        qd = Jx @ qvel
        qdd = Jx @ qacc + np.asarray(Jdv(qpos, qvel), float).ravel()
        tau_sym = inverse_dynamics(q[None], qd[None], qdd[None], PARAMS)[0]
        worst = max(worst, np.abs(Jx.T @ tau_sym - tau_mj).max())
        scale = max(scale, np.abs(tau_mj).max())
    assert scale > 5.0
    assert worst < 1e-9 * scale


def test_regressor_reproduces_simulated_torques_exactly():
    """On a closed-loop MuJoCo run, Y pi == measured motor efforts and 0 on the swing rows."""
    truth = CraneTruth(params=PARAMS)
    res = simulate(truth, 4.0, decimate=20)
    model = build_mjcf(truth)
    data = mujoco.MjData(model)
    h, J, Jdv = _mujoco_to_contract_map()
    q, qd, qdd, tau = [], [], [], []
    for k in range(0, len(res.t), 4):
        data.qpos[:], data.qvel[:] = res.qpos[k], res.qvel[k]
        data.ctrl[:] = res.motor[k]   # motors (no PD bias in this model): same forces
        mujoco.mj_forward(model, data)
        Jx = np.asarray(J(res.qpos[k]), float)
        q.append(np.asarray(h(res.qpos[k]), float).ravel())
        qd.append(Jx @ res.qvel[k])
        qdd.append(Jx @ data.qacc + np.asarray(Jdv(res.qpos[k], res.qvel[k]), float).ravel())
        tau.append(res.motor[k])
    q, qd, qdd, tau = map(np.array, (q, qd, qdd, tau))
    np.testing.assert_allclose(q, res.q[::4], atol=1e-12)       # library map == sympy map
    np.testing.assert_allclose(qd, res.qd[::4], atol=1e-10)
    # and both agree with MuJoCo's own payload position (CONTRACT sec. 2 kinematics)
    from cablelab.plants.crane.kinematics import payload_position
    pay = payload_position(*res.q[:, :5].T, PARAMS.boom_length)
    np.testing.assert_allclose(pay, res.payload, atol=1e-12)
    Y = regressor(q, qd, qdd, PARAMS.gravity)
    pred = Y @ PARAMS.groups()
    assert np.abs(tau).max() > 1.0
    np.testing.assert_allclose(pred[:, :3], tau, atol=1e-8)
    np.testing.assert_allclose(pred[:, 3:], 0.0, atol=1e-8)


def test_gravity_vector_matches_002_eq_6_9():
    rng = np.random.default_rng(1)
    q = rng.uniform(-1, 1, (50, 5))
    q[:, 2] = rng.uniform(0.2, 2, 50)
    p = PARAMS
    al, be, d, t1, t2 = q.T
    g, lb, m, mb, lc, mc = p.gravity, p.boom_length, p.payload_mass, p.boom_mass, p.counterbalance_distance, p.counterbalance_mass
    G = np.stack([0 * al, 0.5 * g * np.cos(be) * (2 * lb * m + lb * mb - 2 * lc * mc),
                  -g * m * np.cos(t1) * np.cos(t2), g * m * np.cos(t2) * np.sin(t1) * d,
                  g * m * np.cos(t1) * np.sin(t2) * d], axis=1)
    np.testing.assert_allclose(gravity_vector(q, p), G, atol=1e-12)


def test_mass_matrix_symmetric_positive_definite():
    rng = np.random.default_rng(2)
    q = rng.uniform(-1.4, 1.4, (200, 5))
    q[:, 2] = rng.uniform(0.1, 2, 200)
    M = mass_matrix(q, PARAMS)
    np.testing.assert_allclose(M, M.transpose(0, 2, 1), atol=1e-12)
    assert np.linalg.eigvalsh(M).min() > 0
