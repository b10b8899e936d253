"""A7 identification round trip (spec 000_suspended.md sec. 6 ii): 7 LiCAS unforced experiments
from the nominal virtual-joint model plus 1 mm / 0.5 deg pose noise, Pearson fit (000 eq. 3-7)
from the Table 5 p_0 within its bounds, then the amplitude-aware NMSE fit from there."""
import numpy as np
import pytest

from cablelab.plants.suspended.identify import (identify, licas_experiments, metrics,
                                                  simulate_experiments, validate, Experiment)
from cablelab.plants.suspended.params import parameter_set

NAMES = ["l9z", "kp7", "kp10", "kd10", "fv7", "fv8", "fv9"]


def _period(t, x):
    x = x - x.mean()
    z = np.where((x[:-1] < 0) & (x[1:] >= 0))[0]
    tz = t[z] - x[z] * (t[z + 1] - t[z]) / (x[z + 1] - x[z])
    return float(np.diff(tz).mean())


@pytest.fixture(scope="module")
def fits():
    p = parameter_set("licas")
    ide, val = licas_experiments(p, duration=6.0, seed=3)
    pear = identify(ide, p, NAMES, objective="pearson", max_iter=8)
    nm = identify(ide, p, NAMES, objective="nmse", start=pear.values, max_iter=6)
    return p, ide, val, pear, nm


def test_a7_pearson_round_trip(fits):
    p, ide, val, pear, _ = fits
    assert pear.mean_R >= 0.97                        # paper 0.9715
    for v in validate(pear.params, val):
        assert np.all(v["rho"][v["use"]] >= 0.95), v
    # the start really was far: Table 5 p_0 of k_p,10 is 10 N m/rad, the truth 0.021
    assert all(0.0 <= pear.values[n] for n in NAMES)


def test_a7_frequencies_within_one_percent(fits):
    p, _, _, pear, nm = fits
    long = [Experiment("y", np.arange(1, 2001) * 0.01, np.zeros((2000, 3)),
                       {"J8": 0.12, "J11": -0.12}, 20.0),
            Experiment("yaw", np.arange(1, 2001) * 0.01, np.zeros((2000, 3)), {"J7": 0.4}, 20.0)]
    t = long[0].t
    truth = simulate_experiments(p, long)[0]
    # the identified model (Pearson, then NMSE from there) within 1 %; the Pearson stage alone
    # leaves the yaw period within 3 % (Pearson is blind to the k_p10 / k_d10 trade-off)
    for fit, tol_yaw in ((nm, 0.01), (pear, 0.03)):
        got = simulate_experiments(fit.params, long)[0]
        assert _period(t, got[0][:, 1]) == pytest.approx(_period(t, truth[0][:, 1]), rel=0.01)
        assert _period(t, got[1][:, 2]) == pytest.approx(_period(t, truth[1][:, 2]), rel=tol_yaw)


def test_amplitude_aware_fit_mre_below_10_percent(fits):
    _, _, val, pear, nm = fits
    mre_nm = [v["mre"][v["use"]] for v in validate(nm.params, val)]
    assert max(np.max(m) for m in mre_nm) < 0.10
    assert nm.fit.nmse <= pear.fit.nmse * (1 + 1e-9)   # NMSE stage never worsens its own cost


def test_metrics_against_closed_forms():
    t = np.linspace(0, 10, 1001)
    y = np.sin(t)[:, None]
    m = metrics(y, 2 * y + 1)                          # gain and offset: rho = 1, MRE large
    assert m["rho"][0] == pytest.approx(1.0)
    assert m["mre"][0] > 1.0
    m = metrics(y, -y)
    assert m["rho"][0] == pytest.approx(-1.0) and m["mre"][0] == pytest.approx(2.0)
