"""002's story through the workbench: tilted base, missing counterbalance, a clean control run."""
from functools import partial

import numpy as np
import pytest

from cablelab.description import load_description
from cablelab.diagnose import rank_candidates
from cablelab.fit import identify
from cablelab.model import Model
from cablelab.plants.crane import dataset as CD
from cablelab.plants.crane import plant as C
from cablelab.plants.crane.model import CraneParams
from cablelab.plants.crane.sim import CraneTruth, gravity_in_base, reference_trajectory, simulate

DESC = load_description(C.__file__.replace("plant.py", "data/crane.yaml"))
P = CraneParams.from_description(DESC)
REST = (0.0, 0.5, 0.6)
#: tilt about world x that puts -0.2 N m on the slew joint at rest at REST (002 sec. 6.5)
TILT_X = -float(np.arcsin(0.2 / np.cos(REST[1]) / P.first_moment / P.gravity))
KNOWN_LC = {"l_c": DESC.crane.counterbalance.distance}


def _dataset(truth, desc, seed, duration=50.0):
    r = simulate(truth, duration, decimate=10, seed=seed,
                 reference=partial(reference_trajectory, base_freq=0.08, seed=seed))
    return CD.dataset_from_arrays(r.t, r.q[:, :3], r.effort, r.t, r.tip, r.payload, desc)


def _hold(t):
    n = len(t)
    return np.tile(REST, (n, 1)), np.zeros((n, 3)), np.zeros((n, 3))


@pytest.fixture(scope="module")
def tilted():
    return _dataset(CraneTruth(params=P, base_tilt=(TILT_X, 0.0)), DESC, seed=0)


def test_slew_torque_at_rest_shows_the_tilt_offset():
    """002 eq. 6.9-6.10: the model says tau_1 = 0 at rest; the tilted base reads about -0.2 N m."""
    r = simulate(CraneTruth(params=P, base_tilt=(TILT_X, 0.0)), 10.0, reference=_hold)
    model_tau1 = 0.0  # G_1 = 0 (002 eq. 6.9)
    rest = r.t > 4.0
    residual = r.effort[rest, 0].mean() - model_tau1
    assert residual == pytest.approx(-0.2, abs=0.01)
    level = simulate(CraneTruth(params=P), 10.0, reference=_hold)
    assert abs(level.effort[level.t > 4.0, 0].mean()) < 1e-3


def test_diagnose_ranks_base_tilt_first(tilted):
    d = rank_candidates(Model("crane", C.baseline(DESC), KNOWN_LC), tilted, C.candidates(DESC))
    best = d.ranking[0]
    assert best.effect == "base_tilt" and best.significant
    assert best.error_after < 0.1 * best.error_before
    # its parameters are the tilt angles: tilt_x = -g_y / g, tilt_y = g_x / g = 0 (002 sec. 6.5)
    g = gravity_in_base(CraneTruth(params=P, base_tilt=(TILT_X, 0.0)))
    assert best.params["tilt_x"] == pytest.approx(-g[1] / P.gravity, rel=0.02)
    assert abs(best.params["tilt_y"]) < 0.02 * abs(TILT_X)


def test_base_tilt_makes_identified_parameters_physical_again(tilted):
    base = identify(Model("crane", C.baseline(DESC), KNOWN_LC), tilted)
    # without the tilt the inertias hit their physical bound (002 sec. 6.2: negative values)
    assert base.linear.active_bounds
    with_tilt = identify(Model("crane", C.baseline(DESC) + ("base_tilt",), KNOWN_LC), tilted)
    assert not with_tilt.linear.active_bounds
    truth = {"I_tot": P.slew_inertia, "I_b": P.luff_inertia, "m": P.payload_mass,
             "m_b": P.boom_mass, "m_c": P.counterbalance_mass}
    for k, v in truth.items():
        assert with_tilt.params[k] == pytest.approx(v, rel=0.1), k
    err = lambda ident: float(np.sqrt(np.nanmean(ident.residual ** 2)))
    assert err(with_tilt) < 0.1 * err(base)


def test_missing_counterbalance_is_ranked_first():
    desc = load_description(DESC.to_yaml().replace("  counterbalance: {mass: 2.0, distance: 0.3}\n", ""))
    assert desc.crane.counterbalance is None
    ds = _dataset(CraneTruth(params=P), desc, seed=1)
    d = rank_candidates(Model("crane", C.baseline(desc), {}), ds, C.candidates(desc))
    assert d.ranking[0].effect == "counterbalance" and d.ranking[0].significant
    # with the boom mass measured (002 fixed measurable parameters) m_c and l_c are identified
    ident = identify(Model("crane", C.baseline(desc) + ("counterbalance",), {"m_b": P.boom_mass}), ds)
    assert ident.params["m_c"] == pytest.approx(P.counterbalance_mass, rel=0.05)
    assert ident.params["l_c"] == pytest.approx(P.counterbalance_distance, rel=0.05)


def test_control_bag_nothing_significant():
    # sensor noise as on the lab crane (about 1 % of each drive's effort): on a noise-free record
    # the simulator's zero-order hold (the command recorded at a step acts over the next 1 ms
    # step, an apparent -0.5 ms delay) is itself a significant effect
    ds = _dataset(CraneTruth(params=P, effort_noise=(0.01, 0.03, 0.05)), DESC, seed=2)
    d = rank_candidates(Model("crane", C.baseline(DESC), KNOWN_LC), ds, C.candidates(DESC))
    assert not any(r.significant for r in d.ranking)


def test_002_group_fit_goes_negative_without_tilt_and_is_physical_with_it(tilted):
    """002 sec. 6.2: the least squares gave negative inertias; the tilt columns fix it."""
    from cablelab.plants.crane.effects import tilt_columns
    from cablelab.effects.base import Param
    from cablelab.plants.crane.identify import FIX_002, identify_groups, physical_check
    from cablelab.plants.crane.model import PARAM_GROUPS

    pi = P.groups()
    fixed = {k: pi[PARAM_GROUPS.index(k)] for k in FIX_002}
    s = tilted.signals
    plain = identify_groups(s["q"], s["qd"], s["qdd"], tilted.y, fixed=fixed, bounded=False, rows=3)
    assert physical_check(plain.values, P.boom_length)          # negative groups
    cols = [Param(n, "", 0.0) for n in ("tilt_a", "tilt_b", "tilt_pa", "tilt_pb")]
    fixed_fit = identify_groups(s["q"], s["qd"], s["qdd"], tilted.y, fixed=fixed, bounded=False,
                                rows=3, extra_columns=tilt_columns(s["q"]), extra_params=cols)
    assert physical_check(fixed_fit.values, P.boom_length) == []
    np.testing.assert_allclose(fixed_fit.pi, pi, rtol=0.15)


@pytest.mark.parametrize("truth_kw, effect, names, values", [
    (dict(viscous=(0.3, 0.3, 2.0)), "joint_viscous_friction", ("Fv[slew]", "Fv[luff]", "Fv[hoist]"), (0.3, 0.3, 2.0)),
    (dict(coulomb=(0.1, 0.1, 0.3)), "joint_coulomb_friction", ("Fc[slew]", "Fc[luff]", "Fc[hoist]"), (0.1, 0.1, 0.3)),
    (dict(torque_offset=(0.1, -0.2, 0.3)), "torque_sensor_offset", ("OF[slew]", "OF[luff]", "OF[hoist]"), (0.1, -0.2, 0.3)),
])
def test_generic_joint_effects_in_the_truth_are_found(truth_kw, effect, names, values):
    ds = _dataset(CraneTruth(params=P, **truth_kw), DESC, seed=3, duration=40.0)
    d = rank_candidates(Model("crane", C.baseline(DESC), KNOWN_LC), ds, C.candidates(DESC))
    best = d.ranking[0]
    assert best.effect == effect and best.significant
    for n, v in zip(names, values):
        assert best.params[n] == pytest.approx(v, rel=0.1, abs=0.01), n
