"""Crane kinematics and swing estimation vs independent formulas (CONTRACT sec. 2, 002 sec. 5.1.3, 6.3)."""
import numpy as np
import pytest

from cablelab.errors import CablelabError
from cablelab.plants.crane.kinematics import (absolute_frame_swing_002, boom_tip, payload_position,
                                              swing_from_positions)
from cablelab.plants.crane.swing import SwingTracker, estimate_swing

LB = 1.3


def _traj(n=4000, dt=0.01):
    t = np.arange(n) * dt
    a = 2.5 * np.sin(0.2 * t) + 1.0                  # crosses +-pi when wrapped
    b = 0.5 + 0.2 * np.sin(0.31 * t)
    d = 0.9 + 0.2 * np.sin(0.13 * t)
    t1 = 0.3 * np.sin(2.1 * t)
    t2 = 0.25 * np.cos(1.7 * t)
    rates = (0.5 * np.cos(0.2 * t), 0.2 * 0.31 * np.cos(0.31 * t), 0.026 * np.cos(0.13 * t),
             0.63 * np.cos(2.1 * t), -0.425 * np.sin(1.7 * t))
    return t, (a, b, d, t1, t2), rates


def test_contract_positions_follow_the_printed_formula():
    a, b, d, t1, t2 = 0.7, 0.4, 0.8, 0.2, -0.1
    tip = LB * np.array([np.cos(b) * np.cos(a), np.cos(b) * np.sin(a), np.sin(b)])
    rz = np.array([[np.cos(a), -np.sin(a), 0], [np.sin(a), np.cos(a), 0], [0, 0, 1]])
    pay = tip + rz @ (d * np.array([np.sin(t2), np.sin(t1) * np.cos(t2), -np.cos(t1) * np.cos(t2)]))
    np.testing.assert_allclose(boom_tip(a, b, LB), tip, atol=1e-15)
    np.testing.assert_allclose(payload_position(a, b, d, t1, t2, LB), pay, atol=1e-15)


def test_exact_inverse_round_trip_large_angles():
    rng = np.random.default_rng(0)
    n = 10000
    a = rng.uniform(-10, 10, n)
    b = rng.uniform(-1.4, 1.4, n)
    d = rng.uniform(0.05, 3, n)
    t1 = rng.uniform(-1.5, 1.5, n)
    t2 = rng.uniform(-1.5, 1.5, n)
    e1, e2, ed = swing_from_positions(boom_tip(a, b, LB), payload_position(a, b, d, t1, t2, LB), a)
    np.testing.assert_allclose(e1, t1, atol=1e-12)
    np.testing.assert_allclose(e2, t2, atol=1e-12)
    np.testing.assert_allclose(ed, d, atol=1e-12)


def test_absolute_frame_002_swaps_the_angles_at_90_degrees_but_ours_does_not():
    """002 sec. 6.3: the same swing seen at alpha = 0 and 90 deg; eq. 5.2-5.3 swap theta1/theta2."""
    t1, t2 = 0.15, 0.0
    est = []
    wrong = []
    for a in (0.0, np.pi / 2):
        tip = boom_tip(a, 0.3, LB)
        pay = payload_position(a, 0.3, 1.0, t1, t2, LB)
        est.append(np.array(swing_from_positions(tip[None], pay[None], np.array([a])))[:2, 0])
        wrong.append(np.array(absolute_frame_swing_002(tip[None], pay[None]))[:, 0])
    np.testing.assert_allclose(est[0], [t1, t2], atol=1e-12)
    np.testing.assert_allclose(est[1], [t1, t2], atol=1e-12)
    assert abs(wrong[0][0]) == pytest.approx(t1, rel=0.05) and abs(wrong[0][1]) < 1e-12
    assert abs(wrong[1][0]) < 1e-12 and abs(wrong[1][1]) == pytest.approx(t1, rel=0.05)  # swapped


def test_002_eq_6_6_6_7_are_small_angle_approximations():
    t1, t2 = 0.05, -0.04
    d_ = 1.0 * np.array([np.sin(t2), np.sin(t1) * np.cos(t2), -np.cos(t1) * np.cos(t2)])
    x, y, z = d_
    th1_002 = -np.arcsin(y / np.hypot(x, z))   # 002 eq. 6.6 (its sign convention for theta1)
    th2_002 = np.arcsin(x / np.hypot(y, z))    # 002 eq. 6.7
    assert abs(abs(th1_002) - t1) < 1e-3 and abs(th2_002 - t2) < 1e-3
    assert abs(abs(th1_002) - t1) > 1e-6 or abs(th2_002 - t2) > 1e-6   # not exact


def test_estimate_swing_wrap_dropout_frozen_irregular():
    t, (a, b, d, t1, t2), rates = _traj()
    rng = np.random.default_rng(1)
    t_irr = t + rng.uniform(-0.003, 0.003, t.size)      # irregular sample times
    t_irr[::97] += 0.004
    t_irr = np.sort(t_irr)
    # evaluate the trajectory at the irregular times
    s = t_irr
    a = 2.5 * np.sin(0.2 * s) + 1.0
    b = 0.5 + 0.2 * np.sin(0.31 * s)
    d = 0.9 + 0.2 * np.sin(0.13 * s)
    t1 = 0.3 * np.sin(2.1 * s)
    t2 = 0.25 * np.cos(1.7 * s)
    tip = boom_tip(a, b, LB)
    pay = payload_position(a, b, d, t1, t2, LB)
    lost = rng.random(s.size) < 0.05
    lost[:3] = False
    tip[lost] = np.nan
    frozen_t = s.copy()
    frozen_t[500:503] = frozen_t[499]                   # frozen stamps
    wrapped_alpha = np.angle(np.exp(1j * a))            # joint encoder wrapping at +-pi
    sw, rep = estimate_swing(frozen_t, tip, pay, s, wrapped_alpha)
    assert rep.dropouts == lost[np.r_[0:500, 503:s.size]].sum()
    assert rep.frozen_stamps == 3
    assert rep.slew_wraps > 0 and rep.irregular_periods > 0
    keep = np.r_[0:500, 503:s.size]
    ok = sw.valid
    np.testing.assert_allclose(sw.theta1[ok], t1[keep][ok], atol=1e-12)
    np.testing.assert_allclose(sw.theta2[ok], t2[keep][ok], atol=1e-12)
    assert np.abs(sw.theta1[~ok] - t1[keep][~ok]).max() < 1e-3     # interpolated across dropouts
    # velocities on the irregular grid vs the analytic rates
    t1d = 0.63 * np.cos(2.1 * s[keep])
    inner = slice(5, -5)
    assert np.abs(sw.theta1_dot - t1d)[inner].max() < 0.02
    assert set(rep.problems()) and "dropouts" in rep.problems()[0]


def test_estimate_swing_bad_input_is_one_line_error():
    with pytest.raises(CablelabError, match="stamps"):
        estimate_swing(np.zeros(3), np.zeros((4, 3)), np.zeros((4, 3)), [0, 1], [0, 0])
    with pytest.raises(CablelabError, match="finite poses"):
        estimate_swing([0, 1, 2], np.full((3, 3), np.nan), np.zeros((3, 3)), [0, 1], [0, 0])


def test_live_tracker_matches_offline_and_reports():
    t, (a, b, d, t1, t2), _ = _traj(n=600)
    tip, pay = boom_tip(a, b, LB), payload_position(a, b, d, t1, t2, LB)
    tr = SwingTracker(tau=0.0)
    out = []
    for k in range(t.size):
        st, x, v = tr.update(t[k], tip[k], pay[k], a[k])
        out.append(x)
    out = np.array(out)
    np.testing.assert_allclose(out[:, 0], t1, atol=1e-12)
    np.testing.assert_allclose(out[:, 2], d, atol=1e-12)
    assert tr.update(t[-1], tip[-1], pay[-1], a[-1])[0] == "frozen"
    assert tr.update(t[-1] + 0.01, [np.nan] * 3, pay[-1], a[-1])[0] == "dropout"
    assert tr.counts["irregular"] == 0
    assert tr.update(t[-1] + 0.03, tip[-1], pay[-1], a[-1])[0] == "ok"      # 3 periods: irregular
    assert tr.counts["irregular"] == 1
    assert tr.update(t[-1] + 5.0, tip[-1], pay[-1], a[-1])[0] == "gap"
    assert tr.counts["frozen"] == 1 and tr.counts["dropout"] == 1 and tr.counts["gap"] == 1
