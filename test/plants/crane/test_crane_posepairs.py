"""Pose pairs meet the slew angle of their stamp (plants/crane/posepairs.py), whatever order the
topics delivered them in: the oracle is the slew angle as a known function of time."""
import numpy as np
import pytest

from cablelab.plants.crane.posepairs import PairedSwing, PosePairs


def slew(t):
    return 3.0 * t          # rad: past pi within the run (the buffer interpolates unwrapped)


def test_pairs_wait_for_their_slew_angle_and_come_out_in_stamp_order():
    p = PosePairs(max_wait=0.045)
    tt = 1.0 + 0.01 * np.arange(10)
    for t in tt[:4]:                        # poses first: nothing is ready without the angle
        p.tip_pose(t, np.array([t, 0, 0]))
        p.payload_pose(t, np.array([t, 0, -1]))
    assert list(p.ready()) == []
    for t in tt[:3]:
        p.slew(t, np.angle(np.exp(1j * slew(t))))       # wrapped to (-pi, pi]
    out = list(p.ready())
    assert [o[0] for o in out] == pytest.approx(tt[:3]) and len(p.pending) == 1
    assert [o[3] for o in out] == pytest.approx([slew(t) for t in tt[:3]], abs=1e-12)
    assert all(o[1][0] == o[0] and o[2][2] == -1 for o in out)
    p.slew(tt[1], 0.0)                                  # older than the newest: ignored
    p.slew(float("nan"), 0.0)
    assert len(p.slews) == 3
    # the angle of stamp tt[3] never comes: the pair waits max_wait (in stamps), then the latest
    for t in tt[4:]:
        p.tip_pose(t, np.zeros(3))
        p.payload_pose(t, np.zeros(3))
    out = list(p.ready())                 # those at least max_wait older than the newest pair
    assert [o[0] for o in out] == pytest.approx(tt[3:5]) and p.unsynced == 2
    assert out[0][3] == pytest.approx(np.angle(np.exp(1j * slew(tt[2]))))
    # a payload pose without the tip pose of its stamp is counted, not paired
    p.payload_pose(5.0, np.zeros(3))
    assert p.unpaired == 1 and len(p.pending) == 5


def test_interpolates_between_angles():
    p = PosePairs(max_wait=1.0)
    p.slew(0.0, 0.1)
    p.slew(0.02, 0.3)
    p.tip_pose(0.005, np.zeros(3))
    p.payload_pose(0.005, np.zeros(3))
    (t, _tip, _pay, s), = p.ready()
    assert s == pytest.approx(0.15)


def test_paired_swing_estimates_each_pair_and_reports_dropouts():
    """The live estimator's core: pairs with their slew angle through the swing tracker, in stamp
    order; a vertical rope from the boom tip is theta1 = theta2 = 0 and the tip-payload distance
    (oracle: the geometry); a NaN pair is a dropout named in the report, not an estimate."""
    ps = PairedSwing(max_wait=0.05, velocity_tau=0.02)
    for k in range(3):
        t = 1.0 + 0.01 * k
        ps.pairs.tip_pose(t, np.array([0.3, 0.2, 1.0]))
        ps.pairs.payload_pose(t, np.array([0.3, 0.2, 0.4]))
        ps.pairs.slew(t, 0.7)
    out = list(ps.estimates())
    assert [o[0] for o in out] == pytest.approx([1.0, 1.01, 1.02])
    np.testing.assert_allclose(out[-1][1], [0.0, 0.0, 0.6], atol=1e-12)
    np.testing.assert_allclose(out[-1][2], 0.0, atol=1e-9)
    problem, values = ps.report()
    assert problem == "" and values["samples ok"] == "3" and values["unpaired poses"] == "0"
    ps.pairs.tip_pose(1.03, np.full(3, np.nan))
    ps.pairs.payload_pose(1.03, np.full(3, np.nan))
    ps.pairs.slew(1.03, 0.7)
    assert list(ps.estimates()) == []
    problem, values = ps.report()
    assert problem.startswith("1 motion-capture dropouts") and values["samples dropout"] == "1"
