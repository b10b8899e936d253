"""The live payload window (ROS-free) of the camera robot: joint states and cable tensions that
arrive out of step across topics are paired by stamp; the fit finds the hidden camera mass
(oracle: the truth simulator's mass) and equals the batch fit of the same record given with its
tensions directly (second path)."""
import numpy as np
import pytest

from cablelab.description import load_description
from cablelab.plants.mjcf.estimation import payload_estimate
from cablelab.plants.mjcf.examples import CABLECAM, text
from cablelab.plants.mjcf.live import PayloadWindow
from cablelab.plants.mjcf.sim import Hidden, description_yaml, record_all, truth_model

CABLES = ["cable_1", "cable_2", "cable_3", "cable_4"]
MASS = 1.5


@pytest.fixture(scope="module")
def cam():
    desc = load_description(description_yaml(text(CABLECAM), tendons=CABLES, payload_body="carriage"))
    truth = truth_model(text(CABLECAM), Hidden(payload=("carriage", MASS, (0.0, 0.0, -0.1))))
    r = record_all(truth, duration=4.0, seed=3)
    eff = np.nan_to_num(r["effort"])
    return desc, r["t"], r["q"], eff, r["tension"]


@pytest.mark.parametrize("lag", [-7, 0, 7])
def test_tensions_out_of_step_are_paired_by_stamp(cam, lag):
    desc, t, q, eff, ten = cam
    w = PayloadWindow(desc, window=3.0, every=10 ** 9)
    n = len(t)
    for k in range(n + abs(lag)):                  # tension k arrives with joint state k + lag
        if 0 <= k - max(lag, 0) < n:
            j = k - max(lag, 0)
            w.tension(t[j], ten[j])
        if 0 <= k - max(-lag, 0) < n:
            j = k - max(-lag, 0)
            w.state(t[j], q[j], eff[j])
    est = w.fit()
    assert est is not None
    np.testing.assert_allclose(est.m, MASS, rtol=0.05)
    tw, qw, ew, tenw = w.paired()
    keep = t >= tw[0] - 1e-12
    np.testing.assert_array_equal(tw, t[keep])
    np.testing.assert_allclose(tenw, ten[keep], atol=1e-12)
    batch = payload_estimate(t[keep], q[keep], eff[keep], desc, tension=ten[keep], driven=w.driven)
    np.testing.assert_allclose(est.m, batch.m, rtol=1e-12)


def test_states_wait_for_their_tensions(cam):
    desc, t, q, eff, ten = cam
    w = PayloadWindow(desc, window=3.0, every=10 ** 9)
    for j in range(200):
        w.state(t[j], q[j], eff[j])
    assert len(w.paired()[0]) == 0 and w.fit() is None       # no tension yet: nothing fitted
    for j in range(100):
        w.tension(t[j], ten[j])
    assert len(w.paired()[0]) == 100
    w.state(t[199], q[199], eff[199])                          # a repeated stamp is skipped
    assert len(w.states) == 200 and "not after" in w.skips.last_problem


def test_without_a_payload_body_the_window_says_so(cam):
    desc = load_description(description_yaml(text(CABLECAM), tendons=CABLES))
    with pytest.raises(Exception, match="payload_body"):
        PayloadWindow(desc, 3.0, 10)


def test_measured_tendons_without_tensions_is_a_one_line_error(cam):
    desc, t, q, eff, ten = cam
    with pytest.raises(Exception, match=r"measures tendons cable_1.*need their tensions") as e:
        payload_estimate(t, q, eff, desc)
    assert "\n" not in str(e.value)
    with pytest.raises(Exception, match=r"got \(.*, 3\)"):
        payload_estimate(t, q, eff, desc, tension=ten[:, :3])


def test_joint_values_take_the_models_joints_in_order_one_value_each():
    from cablelab.plants.mjcf.live import joint_values

    j = ["a", "b"]
    np.testing.assert_array_equal(joint_values(j, j, [1, 2], np.array([3.0, 4.0])), [1, 2, 3, 4])
    assert joint_values(["b", "a"], j, [1, 2]) is None               # another order
    assert joint_values(j, j, [1, 2], [3]) is None                   # a short array
    assert joint_values(j, j, [1, 2], None) is None                  # a missing field
    assert joint_values(None, j, [1, 2]) is None


def test_tension_values_pick_the_measured_tendons_by_name(cam):
    desc = cam[0]
    w = PayloadWindow(desc, 3.0, 10)
    got = w.tension_values(["cable_3", "spare", "cable_1", "cable_4", "cable_2"], [3.0, 9.0, 1.0, 4.0, 2.0])
    np.testing.assert_array_equal(got, [1.0, 2.0, 3.0, 4.0])
    assert w.tension_values(CABLES[:3], [1.0, 2.0, 3.0]) is None          # a tendon missing
    assert w.tension_values(CABLES, [1.0, 2.0, 3.0]) is None              # names and values differ
    assert w.tension_values(CABLES, None) is None


def test_state_values_zero_the_undriven_joints_effort_and_report_the_window(cam):
    """A joint state's values for the input check: positions then efforts in the model's joint
    order, an undriven joint's effort (not measured: NaN allowed) read as zero; the report gives
    the window's samples and the last fitted mass, and a recent skip as a WARN."""
    desc, t, q, eff, ten = cam
    w = PayloadWindow(desc, window=3.0, every=10 ** 9)
    assert len(w.joints) == 3 and not w.driven.any()     # the carriage moves on its cables alone
    raw = np.full(3, np.nan)                              # (what a driver reports for no motor)
    np.testing.assert_array_equal(w.state_values(w.joints, q[0], raw), np.concatenate([q[0], np.zeros(3)]))
    assert w.state_values(w.joints[::-1], q[0], raw) is None                   # another order
    assert w.state_values(w.joints, q[0], raw[:-1]) is None                    # a short array
    level, msg, values = w.report(0, "ok", {})
    assert (level, msg) == (0, "ok") and values == {"samples in window": "0"}
    for j in range(len(t)):
        w.tension(t[j], ten[j])
        w.state(t[j], q[j], eff[j])
    w.fit()
    w.state(t[-1], q[-1], eff[-1])                                # a repeated stamp: skipped
    level, msg, values = w.report(0, "ok", {})
    assert level == 1 and "not after" in msg and values["payload mass kg"] == f"{w.last.m:.6g}"
