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


def test_planned_law_equals_the_per_sample_law(desc):
    """LiveController.plan + planned_law (the control loop's per-period path: reference terms of
    many stamps vectorised, then a few (n,) operations per period) gives what prepare + law give
    for each stamp, to round-off, with the same status: any config (PD/PDFF, Model I/II, CoM or
    not, friction compensation), fresh or stale estimates, non-finite reference rows and states."""
    from hypothesis import HealthCheck, given, settings, strategies as st

    from cablelab.plants.cdpr.control import PdffConfig

    c, g = desc.cdpr, desc.gravity
    unsaturated = [0]

    @settings(max_examples=60, deadline=None, suppress_health_check=list(HealthCheck), derandomize=True)
    @given(seed=st.integers(0, 2 ** 32 - 1), ff=st.booleans(), model=st.sampled_from(["I", "II"]),
           use_com=st.booleans(), friction=st.booleans(), k=st.integers(1, 40))
    def check(seed, ff, model, use_com, friction, k):
        rng = np.random.default_rng(seed)
        gains = PdffConfig(coulomb=0.3, viscous=0.01) if friction else PdffConfig()
        cfg = ControllerConfig(feedforward=ff, model=model, use_com=use_com, gains=gains, estimate_timeout=0.05)
        planned, oracle = LiveController(c, g, cfg), LiveController(c, g, cfg)
        t = 0.01 * np.arange(k) + rng.uniform(0.0, 5.0)
        P = rng.uniform([-1.0, -1.0, 0.6], [1.0, 1.0, 1.6], (k, 3))
        V, A = rng.normal(0.0, 0.3, (k, 3)), rng.normal(0.0, 1.0, (k, 3))
        for X in (P, V, A):             # now and then a row that is not finite
            X[rng.random(k) < 0.1, rng.integers(0, 3)] = rng.choice([np.nan, np.inf, -np.inf])
        plan = planned.plan(t, P, V, A)
        for i in range(k):
            if rng.random() < 0.3:       # an estimate now and then (the timeout makes some stale)
                m, com = rng.uniform(200.0, 900.0), rng.normal(0.0, 0.1, 2)
                te = t[i] - rng.uniform(0.0, 0.1)
                for ctl in (planned, oracle):
                    ctl.estimate(te, m, com)
            ref = LiveController(c, g, cfg).prepare(t[i], P[i], None, V[i], A[i])
            # near the reference (far from it every torque saturates, hiding the other terms)
            q = (-4000.0 if ref is None else ref.q_des) + rng.normal(0.0, 2.0, 8)
            qd = (0.0 if ref is None else ref.qd_des) + rng.normal(0.0, 5.0, 8)
            if rng.random() < 0.1:
                (q if rng.random() < 0.5 else qd)[rng.integers(0, 8)] = rng.choice([np.nan, np.inf])
            got = planned.planned_law(plan, i, q, qd)
            want = oracle.update(t[i], q, qd, P[i], None, V[i], A[i])
            assert (got is None) == (want is None)
            if want is not None:
                np.testing.assert_allclose(got, want, rtol=1e-12, atol=1e-9)
                unsaturated[0] += int((np.abs(want) < cfg.gains.max_torque - 1e-9).sum())
            assert planned.status == oracle.status

    check()
    assert unsaturated[0] > 1000        # the comparisons were mostly of torques inside the limits


def test_reference_rows_are_the_table_at_each_stamp():
    """ReferenceTable.rows (what the control loop plans from) is ReferenceTable.at of each stamp,
    on the grid and past the end of the table (held)."""
    from cablelab.plants.cdpr.trajectory import ReferenceTable

    tab = ReferenceTable(500.0, 0.3, 4.0)
    n = len(tab._table[0])
    for k0, count in ((0, 7), (400, 300), (n - 5, 20)):
        stamps, pos, vel, acc = tab.rows(k0, count)
        for j, ts in enumerate(stamps):
            assert ts == (k0 + j) / 500.0
            for got, want in zip((pos[j], vel[j], acc[j]), tab.at(ts)):
                np.testing.assert_array_equal(got, want)


def test_reference_law_planned_in_blocks_equals_prepared_per_period(desc):
    """The loop's law planned ``block`` periods at once gives the commands of the same law
    prepared period by period, across block boundaries, off-grid stamps, a new estimate and
    periods without time to spare (no planning: the terms of the next stamp alone)."""
    from cablelab.hardware import HardwareState
    from cablelab.plants.cdpr.loop import ReferenceLaw
    from cablelab.plants.cdpr.trajectory import ReferenceTable

    c, g, rate = desc.cdpr, desc.gravity, 1000.0
    tab = ReferenceTable(rate, 0.05, 3.0)
    fast = ReferenceLaw(LiveController(c, g, ControllerConfig()), tab.at, tab.rows, rate, block=7)
    slow = ReferenceLaw(LiveController(c, g, ControllerConfig()), tab.at)
    rng = np.random.default_rng(5)
    t = 0.0
    for k in range(60):
        t = k / rate if k != 30 else 0.0305      # one stamp off the grid
        st = HardwareState(t, rng.normal(-4000.0, 50.0, 8), rng.normal(0.0, 5.0, 8), np.zeros(8))
        if k == 20:
            for law in (fast, slow):
                assert law.estimate(t, 600.0, [0.02, -0.01])
        a, b = fast.update(st), slow.update(st)
        np.testing.assert_allclose(a, b, rtol=1e-12, atol=1e-9)
        assert fast.status == slow.status
        fast.prepare_next(t + 1.0 / rate, spare=k % 9 != 0)
        slow.prepare_next(t + 1.0 / rate)
    assert fast.prepared_used >= 57 and fast.plan is not None and len(fast.plan) == 7
