"""Regressor identification of 002 ch. 4-5 on MuJoCo data: rank 6, fixing, exact recovery, honest errors."""
from functools import partial

import numpy as np
import pytest

from cablelab.plants.crane.identify import (FIX_002, identify_groups, null_space, physical_check,
                                            stacked_regressor)
from cablelab.plants.crane.model import PARAM_GROUPS, CraneParams
from cablelab.plants.crane.sim import CraneTruth, reference_trajectory, simulate, truth_accelerations

PARAMS = CraneParams(boom_length=1.1, payload_mass=0.6, boom_mass=1.2, counterbalance_mass=1.8,
                     counterbalance_distance=0.35, slew_inertia=0.06, luff_inertia=0.025)


@pytest.fixture(scope="module")
def clean():
    truth = CraneTruth(params=PARAMS)
    res = simulate(truth, 40.0, decimate=10, reference=partial(reference_trajectory, base_freq=0.08, seed=4))
    return res, truth_accelerations(truth, res)


def _e(name):
    v = np.zeros(9)
    v[PARAM_GROUPS.index(name)] = 1.0
    return v


def test_rank_is_6_with_the_three_dependencies_of_eq_4_2(clean):
    res, qdd = clean
    Y, tau = stacked_regressor(res.q, res.qd, qdd, res.effort)
    assert Y.shape == (5 * res.t.size, 9)
    rank, N = null_space(Y)
    assert rank == 6                                    # 002 sec. 5.3.2
    # the dependencies read off the energies: J = lb2_mb/4 + lb2_m + lc2_mc, K = lb_mb/2 - lc_mc
    dirs = [_e("lb2_mb") - 0.25 * _e("lc2_mc"),
            _e("lb2_m") - _e("lc2_mc"), _e("lb_mb") + 0.5 * _e("lc_mc")]
    scale = np.abs(Y).max()
    for v in dirs:
        assert np.abs(Y @ v).max() < 1e-9 * scale
        # and v lies in the computed null space
        c = np.linalg.lstsq(N, v, rcond=None)[0]
        assert np.linalg.norm(v - N @ c) < 1e-6 * np.linalg.norm(v)


def test_fixing_002s_measurable_groups_recovers_the_rest_exactly(clean):
    res, qdd = clean
    pi = PARAMS.groups()
    fixed = {k: pi[PARAM_GROUPS.index(k)] for k in FIX_002}
    fit = identify_groups(res.q, res.qd, qdd, res.effort, fixed=fixed, g=PARAMS.gravity)
    assert fit.fit.rank == 6
    np.testing.assert_allclose(fit.pi, pi, rtol=1e-6)
    assert physical_check(fit.values, PARAMS.boom_length) == []


def test_without_fixing_the_fit_names_the_unidentifiable_groups(clean):
    from cablelab.errors import CablelabError

    res, qdd = clean
    with pytest.raises(CablelabError, match="rank-deficient"):
        identify_groups(res.q, res.qd, qdd, res.effort, g=PARAMS.gravity)


def test_noise_gives_honest_standard_errors(clean):
    """White torque noise: (estimate - truth) / stderr behaves like N(0, 1) over repetitions."""
    res, qdd = clean
    pi = PARAMS.groups()
    fixed = {k: pi[PARAM_GROUPS.index(k)] for k in FIX_002}
    free = [k for k in PARAM_GROUPS if k not in FIX_002]
    rng = np.random.default_rng(11)
    z = []
    for _ in range(20):
        tau = res.effort + rng.normal(size=res.effort.shape) * np.array([0.05, 0.05, 0.1])
        f = identify_groups(res.q, res.qd, qdd, tau, fixed=fixed, g=PARAMS.gravity, bounded=False)
        z.append([(f.values[k] - pi[PARAM_GROUPS.index(k)]) / f.fit.stderr[f.fit.names.index(k)]
                  for k in free])
    z = np.array(z)
    assert np.all(np.isfinite(z))
    assert 0.6 < z.std() < 1.5
    assert np.abs(z).max() < 5


def test_physical_check_flags_negative_and_inconsistent_groups():
    vals = dict(zip(PARAM_GROUPS, PARAMS.groups()))
    assert physical_check(vals, PARAMS.boom_length) == []
    bad = dict(vals, I_tot=-0.01, lb_m=2.0 * vals["lb_m"])
    msgs = physical_check(bad, PARAMS.boom_length)
    assert any("I_tot" in m for m in msgs) and any("lb_m/m" in m for m in msgs)
