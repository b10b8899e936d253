"""All 21 Table 5 (★) virtual-joint parameters identified on truth-plant data (LiCAS on four
length-limited tendons: a rigid quadrifilar pendulum, no virtual gains, no friction), and the
identifiability report of :func:`cablelab.plants.suspended.identify.identify`.

Oracles: a second fit on independent data (the four validation experiments) must agree on every
parameter both fits call determined; validation Pearson values on held-out experiments; and the
physics of the truth plant, which fixes what cannot be determined: its yaw is a stiffness/inertia
ratio (only the period is seen, so izz and kp7 share a weak direction), its cables keep the
platform level rigidly (any stiff levelling gain kp11, kp12 fits), and a compound pendulum's
period does not fix its masses and CoM depths separately (m8, l8z)."""
import time

import numpy as np
import pytest

from cablelab.plants.suspended.identify import (identified_params, identify, licas_experiments,
                                                  validate, values_of)
from cablelab.plants.suspended.params import IDENTIFIED, parameter_set

NAMES = [r[0] for r in IDENTIFIED]


@pytest.fixture(scope="module")
def fits():
    # the 0.7 kg truth platform split over links 10-12 (D3 `total`, as the demo); warm start from
    # the repo values, k_p7 scanned over its Table 5 range (the repo yaw period is 25 % off)
    p = parameter_set("licas").replace(m_plat=0.7 / 3)
    ide, val = licas_experiments(p, plant="truth", duration=3.0, seed=3)
    kw = dict(objective="pearson", start=values_of(p), max_iter=8, scan={"kp7": np.linspace(5, 50, 10)})
    t0 = time.perf_counter()
    a = identify(ide, p, NAMES, **kw)
    wall = time.perf_counter() - t0
    b = identify(val, p, NAMES, **kw)                 # second fit, on the other experiments
    print(f"21-parameter Pearson fit: {wall:.1f} s, {a.fit.evaluations} rollouts of 3 x 3 s, "
          f"R {a.mean_R:.5f}, condition {a.report['condition']:.3g}, undetermined {a.undetermined}")
    return p, ide, val, a, b


def test_full_fit_reproduces_held_out_experiments(fits):
    _, _, val, a, _ = fits
    assert len(a.values) == 21 and a.mean_R >= 0.99
    rows = validate(a.params, val)
    rho = np.concatenate([r["rho"][r["use"]] for r in rows])
    print(f"held-out validation rho: min {rho.min():.4f}, mean {rho.mean():.4f}; weak directions "
          f"{[[n for n, _ in d] for d in a.report['weak_directions']]}")
    assert rho.min() >= 0.99 and rho.mean() >= 0.99, rho
    bounds = {q.name: (q.lower, q.upper) for q in identified_params("licas")}
    assert all(bounds[n][0] <= v <= bounds[n][1] for n, v in a.values.items())   # Table 5 bounds


def test_report_names_what_the_truth_plant_cannot_show(fits):
    _, _, _, a, b = fits
    for fit in (a, b):
        rep = fit.report
        assert rep["condition"] > 1e3                        # ill-conditioned: said, not hidden
        und = set(fit.undetermined)
        assert {"kp11", "kp12"} <= und                       # rigid levelling: any stiff gain fits
        assert {"m8", "l8z"} <= und                          # compound pendulum: period only
        # the yaw period fixes kp7 / izz only: one weak direction moves both the same way
        yaw = [dict(d) for d in rep["weak_directions"] if {"izz", "kp7"} <= set(dict(d))]
        assert yaw and np.sign(yaw[0]["izz"]) == np.sign(yaw[0]["kp7"]), rep["weak_directions"]
        assert len(und) < 21                                 # ... but not everything


def test_determined_parameters_agree_between_independent_fits(fits):
    _, _, _, a, b = fits
    both = [n for n in NAMES if n not in a.undetermined and n not in b.undetermined]
    assert both, (a.undetermined, b.undetermined)
    span = {q.name: q.upper - q.lower for q in identified_params("licas")}
    for n in both:
        se = np.hypot(a.report["stderr"][n], b.report["stderr"][n])
        assert abs(a.values[n] - b.values[n]) <= 3 * se + 0.02 * span[n], (n, a.values[n], b.values[n], se)
    # the truth has no cable-joint friction: determined friction parameters come out near zero
    for n in both:
        if n.startswith(("fv", "fs")):
            assert a.values[n] < 3 * a.report["stderr"][n] + 0.02 * span[n], (n, a.values[n])
