"""The CDPR estimator's and controller's cross-topic sample handling (plants/cdpr/streams.py)
without ROS: the oracle is the per-sample law (LiveEstimator / LiveController.update) on the
samples of the same stamp, whatever order the topics delivered them in."""
from types import SimpleNamespace

import numpy as np
import pytest

from cablelab.plants.cdpr.live import EstimatorConfig, LiveController, LiveEstimator
from cablelab.plants.cdpr.sim import default_description
from cablelab.plants.cdpr.streams import CommandStream, EstimateStream, controller_config
from cablelab.plants.cdpr.trajectory import pick_and_place

ONE = np.array([1.0, 0.0, 0.0, 0.0])
PARAMS = SimpleNamespace(feedforward=True, nominal_mass=0.0, kp=1.0, kd=0.05, coulomb=0.3, viscous=0.002,
                         min_tension=100.0, preload=1000.0, max_torque=200.0, model="II", estimate_timeout=2.0)


@pytest.fixture(scope="module")
def desc():
    return default_description()


def test_estimates_meet_the_pose_of_their_stamp_and_say_why_not(desc):
    s = EstimateStream(EstimatorConfig())
    ten = np.full(8, 3000.0)
    assert s.sample(0.0, ten) is None and s.skips.last_problem == "waiting for /plant_description"
    s.describe(None, 9.81)
    assert s.estimator is None and "no cdpr section" in s.skips.last_problem
    s.describe(desc.cdpr, desc.gravity)
    assert s.sample(0.0, ten) is None and s.skips.last_problem == "no desired pose yet"
    tt = 2.0 + 1e-3 * np.arange(4)
    tr = pick_and_place(tt)
    for k in range(4):                    # the reference runs ahead of the tensions
        s.pose(tt[k], tr.position[k], ONE, tr.acceleration[k])
    rng = np.random.default_rng(1)
    oracle = LiveEstimator(desc.cdpr, desc.gravity, EstimatorConfig())
    for k in range(3):
        ten = rng.uniform(2000, 4000, 8)
        t, m, com = s.sample(tt[k], ten)
        m0, com0 = oracle.update(tt[k], tensions=ten, position=tr.position[k], quat=ONE,
                                 acceleration=tr.acceleration[k])
        assert t == tt[k] and m == pytest.approx(m0, rel=1e-12) and com == pytest.approx(com0, abs=1e-12)
    assert s.skips.skipped == 2            # (a description without a cdpr section is no sample)
    # batch: only the newest sample of the period is estimated
    s.batch = True
    assert s.sample(tt[1], ten * 0.5) is None and s.sample(tt[2], ten) is None
    t, m, com = s.poll()
    assert t == tt[2] and m == pytest.approx(oracle.update(tt[2], tensions=ten, position=tr.position[2],
                                                           quat=ONE, acceleration=tr.acceleration[2])[0])
    assert s.poll() is None


def test_estimate_report_says_the_worst_problem_then_recent_skips(desc):
    """/diagnostics of the estimator: ERROR while no description configured it, a WARN naming
    the reason of recently skipped samples, the counts and the options."""
    s = EstimateStream(EstimatorConfig())
    s.describe(None, 9.81)
    level, msg, values = s.report(0, "ok", {})
    assert level == 2 and "no cdpr section" in msg
    s.describe(desc.cdpr, desc.gravity)
    s.sample(0.0, np.full(8, 3000.0))
    level, msg, values = s.report(0, "ok", {})
    assert (level, msg) == (1, "skipped samples (no desired pose yet)")
    assert values == {"skipped": "1", "last problem": "no desired pose yet", "model": "II",
                      "tensions": "dynamometer", "pose": "desired"}
    assert s.report(1, "stale tensions", {})[:2] == (1, "stale tensions")   # an input problem first
    s.skips.last_skip = -1e9                                               # not recent any more
    assert s.report(0, "ok", {})[:2] == (0, "ok")


def test_commands_wait_for_the_reference_of_their_stamp(desc):
    cfg = controller_config(PARAMS, desc.cdpr.platform_mass)
    assert cfg.nominal_mass == desc.cdpr.platform_mass and cfg.gains.kp == 1.0
    s = CommandStream(True, sync_wait=0.005, estimate_wait=0.0)
    s.describe(desc.cdpr, desc.gravity, cfg)
    oracle = LiveController(desc.cdpr, desc.gravity, cfg)
    tt = 1.0 + 1e-3 * np.arange(3)
    tr = pick_and_place(tt)
    q, qd = np.full(8, -4000.0), np.zeros(8)
    s.reference(tt[0], tr.position[0], ONE, tr.velocity[0], tr.acceleration[0])
    s.state((tt[1], [], q, qd, None), now=10.0)         # its reference is not here yet
    assert s.ready() is None and s.ready(now=10.004) is None
    s.reference(tt[1], tr.position[1], ONE, tr.velocity[1], tr.acceleration[1])
    state = s.ready()
    assert state[0] == tt[1] and s.pending is None
    want = oracle.update(tt[1], q, qd, tr.position[1], ONE, tr.velocity[1], tr.acceleration[1])
    np.testing.assert_allclose(s.torques(tt[1], q, qd), want, rtol=1e-12)
    # prepared ahead: the next stamp's terms, used once, equal to the law computed then
    s.reference(tt[2], tr.position[2], ONE, tr.velocity[2], tr.acceleration[2])
    s.prepare_next(tt[1])
    assert s.prepared.t == tt[2] and not s.needs_inputs_first(tt[2])
    want = oracle.update(tt[2], q + 1, qd, tr.position[2], ONE, tr.velocity[2], tr.acceleration[2])
    np.testing.assert_allclose(s.torques(tt[2], q + 1, qd), want, rtol=1e-12)
    assert s.prepared_used == 1
    # a state whose reference never comes goes ahead with the latest after sync_wait
    s.state((tt[2] + 1e-3, [], q, qd, None), now=20.0)
    assert s.ready(now=20.001) is None and s.ready(now=20.006) is not None
    # an implausible estimate is counted, a good one prepares again what was prepared with the
    # old mass (at once: off the state -> command path), equal to the law with the new mass
    s.estimate(tt[2], 1e6, np.zeros(3))
    s.prepare_next(tt[1])
    old = s.prepared
    s.estimate(tt[2], 600.0, np.array([0.01, 0.0, np.nan]))
    assert s.estimates_rejected == 1 and s.controller.mass == 600.0
    assert s.prepared is not old and s.prepared.t == tt[2]
    oracle.estimate(tt[2], 600.0, np.array([0.01, 0.0]))
    want = oracle.prepare(tt[2], tr.position[2], ONE, tr.velocity[2], tr.acceleration[2])
    np.testing.assert_allclose(s.prepared.tensions_ff, want.tensions_ff, rtol=1e-12)
    assert not np.allclose(old.tensions_ff, want.tensions_ff)
    # /diagnostics: the counts and the live feedforward mass; ERROR before a description
    level, msg, values = s.report(0, "ok", {}, "PDFF", 7)
    assert values == {"mode": "PDFF", "commands": "7", "skipped": "0", "estimates rejected": "1",
                      "commands prepared ahead": "1", "feedforward mass kg": "600.0"}
    s.skips.skip("bad motor state (NaN, empty or wrong length)")
    assert s.report(level, msg, {}, "PDFF", 7)[1].endswith("bad motor state (NaN, empty or wrong length)")
    fresh = CommandStream(False, sync_wait=0.005, estimate_wait=0.0)
    level, msg, values = fresh.report(0, "ok", {}, "PD", 0)
    assert (level, msg) == (2, "waiting for /plant_description") and values["feedforward mass kg"] == "-"


def test_an_awaited_estimate_holds_the_state_until_it_comes_or_times_out(desc):
    s = CommandStream(True, sync_wait=0.005, estimate_wait=0.05)
    s.describe(desc.cdpr, desc.gravity, controller_config(PARAMS, desc.cdpr.platform_mass))
    tr = pick_and_place(np.array([1.0]))
    s.reference(1.0, tr.position[0], ONE, tr.velocity[0], tr.acceleration[0])
    s.state((1.0, [], np.zeros(8), np.zeros(8), None), now=0.0)
    assert s.waiting_for(1.0) == (False, True) and s.ready() is None and s.ready(now=0.04) is None
    s.estimate(1.0, None, None)                        # a rejected estimate still names its stamp
    assert s.ready() is not None
    s.reference(1.001, tr.position[0], ONE, tr.velocity[0], tr.acceleration[0])
    s.state((1.001, [], np.zeros(8), np.zeros(8), None), now=1.0)
    assert s.ready(now=1.049) is None and s.ready(now=1.051) is not None
    assert not CommandStream(False, 0.005, 0.05).awaits_estimate      # PD: no estimate to wait for


def test_command_checks_law_state_and_reference_in_that_order(desc):
    """A state is commanded only with a law, a good motor state and a fresh reference, checked in
    that order (a state before the description is not shown to the input monitor); the torques
    are the law's (oracle: LiveController.update)."""
    from cablelab.ros.inputs import InputMonitor

    inputs = InputMonitor()
    inputs.add("joint_states", timeout=0.5, length=8)
    inputs.add("reference", timeout=0.5)
    s = CommandStream(True, sync_wait=0.005, estimate_wait=0.0)
    q, qd = np.full(8, -4000.0), np.zeros(8)
    assert s.command((1.0, [], q, qd, None), inputs, 0.0) is None
    assert s.skips.last_problem == "waiting for /plant_description" and inputs.inputs["joint_states"].received == 0
    cfg = controller_config(PARAMS, desc.cdpr.platform_mass)
    s.describe(desc.cdpr, desc.gravity, cfg)
    for bad_q, bad_qd in ((np.full(8, np.nan), qd), (q[:7], qd[:7]), (q, None), (q, qd[:7])):
        assert s.command((1.0, [], bad_q, bad_qd, None), inputs, 0.0) is None
        assert s.skips.last_problem.startswith("bad motor state")
    assert inputs.inputs["joint_states"].rejected == 2          # (the monitor checks positions)
    assert s.command((1.0, [], q, qd, None), inputs, 0.0) is None and "no fresh reference" in s.skips.last_problem
    tr = pick_and_place(np.array([1.0]))
    s.reference(1.0, tr.position[0], ONE, tr.velocity[0], tr.acceleration[0])
    inputs.accept("reference", tr.position[0], 0.0)
    assert s.command((1.0, [], q, qd, None), inputs, 0.6) is None       # the reference went stale
    want = LiveController(desc.cdpr, desc.gravity, cfg).update(1.0, q, qd, tr.position[0], ONE,
                                                               tr.velocity[0], tr.acceleration[0])
    np.testing.assert_allclose(s.command((1.0, [], q, qd, None), inputs, 0.1), want, rtol=1e-12)


def test_a_reference_streamed_50_ms_ahead_meets_its_own_stamp(desc):
    """The simulator streams the reference 50 ms (50 samples at 1 kHz) ahead of its states in
    real time: the controller's command of a state uses the reference of that state's stamp and
    the estimator's estimate of a tension sample the pose of its stamp, not the oldest of a few
    kept samples (which would be ~40 ms in the future)."""
    lead, n = 50, 200
    tt = 2.0 + 1e-3 * np.arange(n + lead)      # (moving at ~0.2 m/s: 50 ms ahead is 1 cm off)
    tr = pick_and_place(tt)
    cfg = controller_config(PARAMS, desc.cdpr.platform_mass)
    cs = CommandStream(True, sync_wait=0.005, estimate_wait=0.0)
    cs.describe(desc.cdpr, desc.gravity, cfg)
    oracle = LiveController(desc.cdpr, desc.gravity, cfg)
    es = EstimateStream(EstimatorConfig())
    es.describe(desc.cdpr, desc.gravity)
    est_oracle = LiveEstimator(desc.cdpr, desc.gravity, EstimatorConfig())
    rng = np.random.default_rng(3)
    q, qd = np.full(8, -4000.0), np.zeros(8)
    for k in range(lead):
        cs.reference(tt[k], tr.position[k], ONE, tr.velocity[k], tr.acceleration[k])
        es.pose(tt[k], tr.position[k], ONE, tr.acceleration[k])
    for k in range(n):
        j = k + lead
        cs.reference(tt[j], tr.position[j], ONE, tr.velocity[j], tr.acceleration[j])
        es.pose(tt[j], tr.position[j], ONE, tr.acceleration[j])
        want = oracle.update(tt[k], q, qd, tr.position[k], ONE, tr.velocity[k], tr.acceleration[k])
        np.testing.assert_allclose(cs.torques(tt[k], q, qd), want, rtol=1e-12)
        cs.prepare_next(tt[k])                  # the next stamp's terms, prepared ahead
        assert cs.prepared.t == tt[k + 1]
        ten = rng.uniform(2000, 4000, 8)
        _, m, com = es.sample(tt[k], ten)
        m0, com0 = est_oracle.update(tt[k], tensions=ten, position=tr.position[k], quat=ONE,
                                     acceleration=tr.acceleration[k])
        assert m == pytest.approx(m0, rel=1e-12) and com == pytest.approx(com0, abs=1e-12)
    assert cs.prepared_used == n - 1
