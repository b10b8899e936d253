"""The single-sample kernels of the live estimator and controller (cablelab.plants.cdpr.live,
used at 1 kHz by the nodes and at every step of ``simulate``) against the batch functions of
geometry / estimation / control (the second implementation): same torques and estimates for
random poses, orientations, rates, masses and CoM, Model I and II, with and without a
precomputed W / W^+."""
import numpy as np
import pytest

from cablelab.plants.cdpr.control import feedforward_tensions, motor_angles, motor_rates, pdff_torques
from cablelab.plants.cdpr.estimation import mass_com
from cablelab.plants.cdpr.geometry import cable_geometry, quat_to_matrix, wrench_matrix
from cablelab.plants.cdpr.live import ControllerConfig, EstimatorConfig, LiveController, LiveEstimator
from cablelab.plants.cdpr.sim import default_description


@pytest.fixture(scope="module")
def desc():
    return default_description()


def _poses(rng, k):
    p = rng.uniform([-1.0, -1.0, 0.6], [1.0, 1.0, 1.6], (k, 3))
    q = np.concatenate([np.ones((k, 1)), rng.normal(0.0, 0.05, (k, 3))], 1)
    q /= np.linalg.norm(q, axis=1, keepdims=True)
    return p, q


@pytest.mark.parametrize("model", ["I", "II"])
def test_live_controller_equals_batch_law(desc, model):
    c, g = desc.cdpr, desc.gravity
    rng = np.random.default_rng(1)
    cfg = ControllerConfig(model=model)
    r = 0.0 if model == "I" else c.pulley_radius
    P, Q = _poses(rng, 20)
    for k in range(len(P)):
        ctl = LiveController(c, g, cfg)
        m, com = rng.uniform(400, 700), rng.uniform(-0.1, 0.1, 2)
        ctl.estimate(0.0, m, com)
        q, qd = rng.normal(-4000, 50, 8), rng.normal(0, 5, 8)
        v, a = rng.normal(0, 0.2, 3), rng.normal(0, 0.3, 3)
        quat = Q[k] if k % 2 else np.array([1.0, 0, 0, 0])
        R = None if k % 2 == 0 else quat_to_matrix(quat)[None]
        geom = cable_geometry(c.exit_points, c.anchor_points, P[k][None], R, r, c.swivel_axes)
        tff = feedforward_tensions(geom, m, a[None], g, np.array([com[0], com[1], 0.0]),
                                   cfg.gains.preload, cfg.gains.min_tension)[0]
        want = pdff_torques(q, qd, motor_angles(geom.lengths, c.drum_radius, c.gear_ratio)[0],
                            motor_rates(geom, v, c.drum_radius, c.gear_ratio)[0], tff,
                            c.drum_radius, c.gear_ratio, cfg.gains)
        got = ctl.update(0.0, q, qd, P[k], quat, v, a)
        np.testing.assert_allclose(got, want, rtol=1e-9, atol=1e-9)
        # the reference terms prepared ahead (before the state is known) + the state part
        ref = ctl.prepare(0.0, P[k], quat, v, a)
        np.testing.assert_allclose(ctl.law(ref, q, qd), want, rtol=1e-9, atol=1e-9)
        assert ctl.law(ref, np.full(8, np.nan), qd) is None and "motor angles" in ctl.status[-1][1]
        W = wrench_matrix(geom)
        got2 = ctl.update(0.0, q, qd, P[k], quat, v, a, geometry=geom, pinv=np.linalg.pinv(W), wrench=W[0])
        np.testing.assert_allclose(got2, want, rtol=1e-7, atol=1e-7)


@pytest.mark.parametrize("model", ["I", "II"])
def test_live_estimator_equals_batch_eq13(desc, model):
    c, g = desc.cdpr, desc.gravity
    rng = np.random.default_rng(2)
    r = 0.0 if model == "I" else c.pulley_radius
    P, Q = _poses(rng, 20)
    for k in range(len(P)):
        for inertia in (False, True):
            est = LiveEstimator(c, g, EstimatorConfig(model=model, platform_inertia=inertia))
            T = rng.uniform(300, 2500, 8)
            a = rng.normal(0, 0.3, 3)
            quat = Q[k] if k % 2 else np.array([1.0, 0, 0, 0])
            R = None if k % 2 == 0 else quat_to_matrix(quat)[None]
            geom = cable_geometry(c.exit_points, c.anchor_points, P[k][None], R, r, c.swivel_axes)
            want = mass_com(geom, T[None], g, a[None] if inertia else None, R)
            got = est.update(0.0, tensions=T, position=P[k], quat=quat, acceleration=a, condition=1.0)
            if not (want.mass[0] > 0):
                assert got is None
                continue
            assert got is not None
            np.testing.assert_allclose(got[0], want.mass[0], rtol=1e-10)
            np.testing.assert_allclose(got[1], want.com[0], rtol=1e-8, atol=1e-10)
            got2 = est.update(0.0, tensions=T, position=P[k], quat=quat, acceleration=a, condition=1.0,
                              wrench=wrench_matrix(geom)[0])
            np.testing.assert_allclose(got2[0], want.mass[0], rtol=1e-10)
