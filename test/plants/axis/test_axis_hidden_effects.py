"""Proof on hidden effects: synthetic axis data (MuJoCo, prismatic and a gravity pendulum) with
effects the analysed model lacks, over magnitudes and noise levels, and control cases.

Oracle: the simulator's true parameters (MuJoCo joint damping, frictionloss, servo force with a
sensor offset / delay added); the analysed model is the plant's nominal one.
"""
import pytest

from cablelab.description import load_description
from cablelab.diagnose import greedy, rank_candidates
from cablelab.model import Model
from cablelab.plants import get_plant
from cablelab.plants.axis.dataset import dataset_from_arrays
from cablelab.plants.axis.sim import AxisTruth
from cablelab.plants.axis.truth import simulate_axis

PRISMATIC = load_description("plant: axis\naxis:\n  joint_type: prismatic\n  inertia: 2.0\n")
PENDULUM = load_description("plant: axis\naxis:\n  joint_type: revolute\n  inertia: 0.3\n"
                            "  gravity_moment: 0.4\n")
AXIS = get_plant("axis")


def _diagnose(desc, truth, *, noise, delay=0.0, seed=0, amplitude=None):
    amp = amplitude or (0.3 if desc.axis.joint_type == "prismatic" else 0.8)
    run = simulate_axis(desc, truth, duration=12.0, fs=500.0, amplitude=amp, noise_effort=noise,
                        noise_position=1e-6, delay=delay, seed=seed)
    ds = dataset_from_arrays(run.t, run.q, run.effort, desc)
    model = Model("axis", AXIS.baseline(desc))
    return ds, model, rank_candidates(model, ds, AXIS.candidates(desc))


# (description, truth, hidden effect, its parameter, true value, effort noise std)
CASES = [
    ("prismatic", dict(coulomb=2.0), "joint_coulomb_friction", "Fc", 2.0, 0.05),
    ("prismatic", dict(coulomb=2.0), "joint_coulomb_friction", "Fc", 2.0, 0.5),
    ("prismatic", dict(coulomb=0.5), "joint_coulomb_friction", "Fc", 0.5, 0.3),
    ("prismatic", dict(offset=1.0), "torque_sensor_offset", "OF", 1.0, 0.05),
    ("prismatic", dict(offset=-0.3), "torque_sensor_offset", "OF", -0.3, 0.3),
    ("prismatic", dict(), "time_delay", "tau", 0.010, 0.05),
    ("pendulum", dict(coulomb=0.2), "joint_coulomb_friction", "Fc", 0.2, 0.02),
    ("pendulum", dict(coulomb=0.2), "joint_coulomb_friction", "Fc", 0.2, 0.1),
    ("pendulum", dict(offset=0.15), "torque_sensor_offset", "OF", 0.15, 0.05),
]


def _truth(kind, extra):
    base = dict(inertia=2.0, viscous=5.0, coulomb=0.0, offset=0.0) if kind == "prismatic" else \
        dict(inertia=0.3, viscous=0.4, coulomb=0.0, offset=0.0)
    base.update(extra)
    return AxisTruth(**base)


@pytest.mark.parametrize("kind,extra,effect,param,value,noise", CASES)
def test_hidden_effect_is_ranked_first_and_recovered(kind, extra, effect, param, value, noise):
    desc = PRISMATIC if kind == "prismatic" else PENDULUM
    delay = value if effect == "time_delay" else 0.0
    ds, model, d = _diagnose(desc, _truth(kind, extra), noise=noise, delay=delay)
    top = d.ranking[0]
    assert top.effect == effect, [(r.effect, r.error_after) for r in d.ranking]
    assert top.significant, top
    assert top.params[param] == pytest.approx(value, rel=0.10)
    assert top.error_after < top.error_before
    # once the hidden effect is in the model, nothing else is significant
    d2 = rank_candidates(model.with_effect(effect), ds, AXIS.candidates(desc))
    assert not any(r.significant for r in d2.ranking), [(r.effect, r.gain) for r in d2.ranking]


@pytest.mark.parametrize("desc,truth", [(PRISMATIC, _truth("prismatic", {})),
                                        (PENDULUM, _truth("pendulum", {}))])
@pytest.mark.parametrize("noise_rel", [0.01, 0.05])
def test_control_nothing_hidden_nothing_significant(desc, truth, noise_rel):
    effort_scale = 7.0 if desc is PRISMATIC else 3.0
    ds, model, d = _diagnose(desc, truth, noise=noise_rel * effort_scale, seed=3)
    assert len(d.ranking) == len(set(AXIS.candidates(desc)) - set(model.effects))
    assert not any(r.significant for r in d.ranking), [(r.effect, r.p_value, r.gain)
                                                          for r in d.ranking]
    # and the nominal model is already at the noise floor
    assert d.baseline_error < 2.5 * noise_rel


def test_effect_below_noise_is_not_marked_significant():
    ds, model, d = _diagnose(PRISMATIC, _truth("prismatic", dict(coulomb=0.01)), noise=0.5, seed=5)
    assert not any(r.significant for r in d.ranking)


@pytest.mark.parametrize("kind,extra,order,noise", [
    ("prismatic", dict(coulomb=1.5, offset=0.5), ("joint_coulomb_friction", "torque_sensor_offset"), 0.1),
    ("pendulum", dict(coulomb=0.08, offset=0.25), ("torque_sensor_offset", "joint_coulomb_friction"), 0.02),
])
def test_two_hidden_effects_greedy_adds_both_larger_first(kind, extra, order, noise):
    desc = PRISMATIC if kind == "prismatic" else PENDULUM
    truth = _truth(kind, extra)
    run = simulate_axis(desc, truth, duration=12.0, amplitude=0.3 if kind == "prismatic" else 0.8,
                        noise_effort=noise, noise_position=1e-6, seed=7)
    ds = dataset_from_arrays(run.t, run.q, run.effort, desc)
    steps = greedy(Model("axis", AXIS.baseline(desc)), ds, AXIS.candidates(desc))
    assert [s.added for s in steps] == [None, *order]
    errs = [s.error for s in steps]
    assert errs[0] > errs[1] > errs[2]
    p = steps[-1].params
    assert p["Fc"] == pytest.approx(truth.coulomb, rel=0.10)
    assert p["OF"] == pytest.approx(truth.offset, rel=0.10)
    assert p["M"] == pytest.approx(truth.inertia, rel=0.03)
    assert p["Fv"] == pytest.approx(truth.viscous, rel=0.05)
    if kind == "pendulum":
        assert p["mc"] == pytest.approx(0.4, rel=0.03)


def test_pendulum_gravity_moment_recovered_as_candidate_when_not_in_the_model():
    desc = load_description("plant: axis\naxis:\n  joint_type: revolute\n  inertia: 0.3\n")
    sim_desc = PENDULUM  # the real pendulum has m c = 0.4 kg m
    run = simulate_axis(sim_desc, _truth("pendulum", {}), amplitude=0.8, noise_effort=0.02, seed=2)
    ds = dataset_from_arrays(run.t, run.q, run.effort, desc)
    d = rank_candidates(Model("axis", AXIS.baseline(desc)), ds, AXIS.candidates(desc))
    assert d.ranking[0].effect == "axis_gravity" and d.ranking[0].significant
    assert d.ranking[0].params["mc"] == pytest.approx(0.4, rel=0.05)
