"""CDPR core (001 eq. 1-15) against independent oracles: finite differences, statics, closed forms."""
import numpy as np
import pytest

from cablelab.description import load_description
from cablelab.plants.cdpr.estimation import (mass_com, mass_com_batch, mass_com_from_wrench,
                                             tensions_from_torques,
                                             torques_from_tensions)
from cablelab.plants.cdpr.geometry import (cable_geometry, cable_wrench, matrix_to_quat,
                                           quat_to_matrix, wrench_matrix)
from cablelab.plants.cdpr.trajectory import pick_and_place, sample_trajectory

CAROCA = "src/cablelab/cablelab/plants/cdpr/data/caroca.yaml"


@pytest.fixture(scope="module")
def caroca():
    return load_description(CAROCA).cdpr


def _rot(rx, ry, rz):
    cx, sx, cy, sy, cz, sz = np.cos(rx), np.sin(rx), np.cos(ry), np.sin(ry), np.cos(rz), np.sin(rz)
    Rx = np.array([[1, 0, 0], [0, cx, -sx], [0, sx, cx]])
    Ry = np.array([[cy, 0, sy], [0, 1, 0], [-sy, 0, cy]])
    Rz = np.array([[cz, -sz, 0], [sz, cz, 0], [0, 0, 1]])
    return Rz @ Ry @ Rx


@pytest.mark.parametrize("r", [0.0, 0.15])
def test_length_gradient_is_cable_direction(caroca, r):
    """d l_i / d p = -d_i (unit vector from B_i to the pulley), by central differences, for both
    models and a tilted platform; and d l_i / d(rotation) gives the moment rows of W (eq. 4, 7)."""
    p = np.array([0.3, -0.2, 1.0])
    R = _rot(0.05, -0.03, 0.1)
    g = cable_geometry(caroca.exit_points, caroca.anchor_points, p, R, r)
    h = 1e-6
    for k in range(3):
        dp = np.zeros(3)
        dp[k] = h
        lp = cable_geometry(caroca.exit_points, caroca.anchor_points, p + dp, R, r).lengths[0]
        lm = cable_geometry(caroca.exit_points, caroca.anchor_points, p - dp, R, r).lengths[0]
        np.testing.assert_allclose((lp - lm) / (2 * h), -g.directions[0, :, k], atol=1e-6)
        # small world rotation about axis k: dl/dtheta = -(R b x d)_k
        Rp = _rot(*(h * np.eye(3)[k])) @ R
        Rm = _rot(*(-h * np.eye(3)[k])) @ R
        lp = cable_geometry(caroca.exit_points, caroca.anchor_points, p, Rp, r).lengths[0]
        lm = cable_geometry(caroca.exit_points, caroca.anchor_points, p, Rm, r).lengths[0]
        W = wrench_matrix(g)[0]
        np.testing.assert_allclose((lp - lm) / (2 * h), -W[3 + k], atol=1e-5)


def test_model2_closed_form_vertical_plane():
    """A pulley at the origin, anchor in the x-z plane: tangent point, wrap angle and length by
    hand (sheave centre (r, 0, 0); cable up the axis, over the top, down to B)."""
    r = 0.2
    A = np.zeros((1, 3))
    B = np.array([[2.0, 0.0, -1.5]])
    g = cable_geometry(A, B, np.zeros(3), None, r)
    O = np.array([r, 0.0, 0.0])
    v = B[0] - O
    D = np.linalg.norm(v)
    lc = np.sqrt(D * D - r * r)
    psi = np.arctan2(v[2], v[0])
    phi = psi + np.arccos(r / D)
    Ap = O + r * np.array([np.cos(phi), 0.0, np.sin(phi)])
    np.testing.assert_allclose(g.tangent_points[0, 0], Ap, atol=1e-12)
    np.testing.assert_allclose(g.wrap_angles[0, 0], np.pi - phi, atol=1e-12)
    np.testing.assert_allclose(g.lengths[0, 0], r * (np.pi - phi) + lc, atol=1e-12)
    # the cable is tangent: radius O->A' is perpendicular to A'->B
    assert abs(np.dot(Ap - O, B[0] - Ap)) < 1e-12
    # 001 eq. 9: l_c = a - r_p (z_p + e) x y_p - b, with y_p = z_p x x_p the sheave axle
    xp, zp = np.array([1.0, 0, 0]), np.array([0, 0, 1.0])
    yp = np.cross(zp, xp)
    e = g.directions[0, 0]
    lc_vec = A[0] - r * np.cross(zp + e, yp) - B[0]
    np.testing.assert_allclose(lc_vec / np.linalg.norm(lc_vec), e, atol=1e-12)
    np.testing.assert_allclose(np.linalg.norm(lc_vec), lc, atol=1e-12)
    # r -> 0 tends to Model I
    g0 = cable_geometry(A, B, np.zeros(3), None, 1e-9)
    g1 = cable_geometry(A, B, np.zeros(3), None, 0.0)
    np.testing.assert_allclose(g0.directions, g1.directions, atol=1e-8)
    np.testing.assert_allclose(g0.lengths, g1.lengths, atol=1e-8)


def test_swivel_angle_is_atan2_and_axis_general():
    A = np.array([[1.0, 2.0, 3.0]])
    B = np.array([[0.4, -0.3, 0.0]])
    g = cable_geometry(A, B, np.zeros(3), None, 0.15)
    np.testing.assert_allclose(g.swivel_angles[0, 0], np.arctan2(-2.3, -0.6), atol=1e-12)
    # any swivel axis: rotating the whole scene rotates the result
    R = _rot(0.3, -0.5, 0.2)
    gR = cable_geometry(A @ R.T, B, np.zeros(3), R, 0.15, swivel_axes=np.array([[0, 0, 1.0]]) @ R.T)
    np.testing.assert_allclose(gR.lengths, g.lengths, atol=1e-12)
    np.testing.assert_allclose(gR.directions[0], g.directions[0] @ R.T, atol=1e-12)


@pytest.mark.parametrize("r", [0.0, 0.15])
def test_mass_com_static_equilibrium(caroca, r):
    """Tensions that balance a known mass and CoM (solved independently with lstsq on W of
    eq. 4/7) give back that mass and CoM through eq. 13; the residual is zero."""
    tr = sample_trajectory(60.0, 2.0)
    g = cable_geometry(caroca.exit_points, caroca.anchor_points, tr.position, None, r)
    W = wrench_matrix(g)
    m, c = 615.0, np.array([0.06, -0.02, -0.25])
    wg = np.concatenate([[0, 0, m * 9.81], np.cross(c, [0, 0, m * 9.81])])
    t = np.stack([np.linalg.lstsq(Wk, wg, rcond=None)[0] for Wk in W])
    est = mass_com(g, t, 9.81, com_z=-0.25)
    np.testing.assert_allclose(est.mass, m, rtol=1e-9)
    np.testing.assert_allclose(est.com, np.broadcast_to(c[:2], est.com.shape), atol=1e-9)
    assert est.residual.max() < 1e-6
    np.testing.assert_allclose(cable_wrench(g, t), np.einsum("tij,tj->ti", W, t), atol=1e-8)


@pytest.mark.parametrize("r", [0.0, 0.15])
def test_batch_kernel_equals_general_path(caroca, r):
    """The fast offline kernel (per-coordinate, chunked) is a second implementation of
    cable_geometry + mass_com: same mass, CoM and residual, also with tilted swivel axes."""
    rng = np.random.default_rng(3)
    N = 5000
    P = np.column_stack([rng.uniform(-1, 1, N), rng.uniform(-0.4, 0.4, N), rng.uniform(0.6, 1.2, N)])
    T = rng.uniform(200, 2000, (N, 8))
    axes = caroca.swivel_axes + 0.1 * rng.standard_normal((8, 3))
    axes /= np.linalg.norm(axes, axis=1, keepdims=True)
    ref = mass_com(cable_geometry(caroca.exit_points, caroca.anchor_points, P, None, r, axes), T)
    fast = mass_com_batch(caroca.exit_points, caroca.anchor_points, P, T, r, 9.81, axes, chunk=777)
    np.testing.assert_allclose(fast.mass, ref.mass, rtol=1e-12)
    np.testing.assert_allclose(fast.com, ref.com, atol=1e-12)
    np.testing.assert_allclose(fast.residual, ref.residual, rtol=1e-9, atol=1e-9)


def test_mass_with_acceleration_and_tilt():
    """Dynamic balance W t = [m f; m c x f], f = a + g z (eq. 10 without rotation terms), tilted
    platform: the platform_inertia variant recovers m and the CoM in the platform frame."""
    rng = np.random.default_rng(1)
    N = 50
    m = 488.0
    c_p = np.array([0.1, -0.05, -0.2])
    R = np.stack([_rot(*(0.05 * rng.standard_normal(3))) for _ in range(N)])
    a = 0.5 * rng.standard_normal((N, 3))
    f = a + [0, 0, 9.81]
    c_w = np.einsum("tij,j->ti", R, c_p)
    w = np.concatenate([m * f, m * np.cross(c_w, f)], 1)
    est = mass_com_from_wrench(w, 9.81, acceleration=a, rotation=R, com_z=-0.2)
    np.testing.assert_allclose(est.mass, m, rtol=1e-12)
    np.testing.assert_allclose(est.com, np.broadcast_to(c_p[:2], (N, 2)), atol=1e-10)
    static = mass_com_from_wrench(w, 9.81)
    assert np.abs(static.mass - m).max() > 10.0      # ignoring m*a is visibly wrong


def test_tension_torque_roundtrip_and_sign():
    v = np.array([[-50.0, -0.0, 0.0, 3.0]])
    t = np.array([[1000.0, 800.0, 0.0, 1200.0]])
    tau = torques_from_tensions(t, v, 0.06, 40.0, coulomb=0.4, viscous=0.004)
    # CONTRACT: effort = r/R t + friction; friction opposes motion (reeling in costs torque)
    np.testing.assert_allclose(tau, [[1.5 - 0.4 - 0.2, 1.2, 0.0, 1.8 + 0.4 + 0.012]])
    np.testing.assert_allclose(tensions_from_torques(tau, v, 0.06, 40.0, 0.4, 0.004), t)


def test_trajectory_scurve_consistent():
    """Velocity and acceleration are the derivatives of position (finite differences); the
    path visits A..E with zero velocity at A, B, D, E, and returns to A at 60 s (001 sec. II-C)."""
    t = np.linspace(-1, 61, 62001)
    tr = pick_and_place(t)
    dt = t[1] - t[0]
    np.testing.assert_allclose(np.gradient(tr.position, dt, axis=0)[1:-1], tr.velocity[1:-1], atol=2e-4)
    np.testing.assert_allclose(np.gradient(tr.velocity, dt, axis=0)[2:-2], tr.acceleration[2:-2], atol=2e-3)
    W = pick_and_place(np.array([0.0, 5.0, 15.0, 25.0, 30.0, 35.0, 55.0, 60.0]))
    from cablelab.plants.cdpr.trajectory import CAROCA_WAYPOINTS as P
    np.testing.assert_allclose(W.position, P[[0, 1, 2, 3, 4, 3, 1, 0]], atol=1e-12)
    np.testing.assert_allclose(W.velocity[[0, 1, 3, 4, 5, 6, 7]], 0.0, atol=1e-12)


def test_quaternion_roundtrip():
    R = np.stack([_rot(0.1, -0.2, 2.5), _rot(3.0, 0.1, -1.0), np.eye(3)])
    np.testing.assert_allclose(quat_to_matrix(matrix_to_quat(R)), R, atol=1e-12)
