"""Diagnosis on realistic drive recordings: fixed-seed cases of the benchmark generator.

Oracle: bench/diagnosis_cases.py integrates the closed-loop drive with scipy solve_ivp and a
SMOOTH friction law (tanh Coulomb band), quantizes the encoder, holds the drive at rest 40 % of
the time, adds coloured effort noise; none of the fitting code is used. Each case is written as a
real bag and read back through cablelab.workbench.load -> diagnose, the `cablelab diagnose` path.
"""
import os
import sys

import numpy as np
import pytest

from cablelab import workbench
from cablelab.errors import CablelabError

sys.path.insert(0, os.path.join(os.path.dirname(__file__), "..", "..", "bench"))
from diagnosis_cases import Case, write_bag  # noqa: E402


def _truth(**kw):
    t = {"M": 6.0, "Fv": 12.0, "mc": 0.0, "Fc": 0.0, "Fs": 0.0, "vs": 0.05, "eps": 0.002,
         "OF": 0.0, "tau": 0.0}
    t.update(kw)
    return t


def _case(seed, hidden, truth, **kw):
    base = dict(seed=seed, flavour="linear", fs=1000.0, duration=10.0, profile="ptp",
                rest_fraction=0.4, hidden=hidden, truth=truth, velocity_recorded=False,
                quantum=2e-6, noise_rel=0.02, ar=0.5, outlier_rate=0.0, vmax=0.5)
    base.update(kw)
    return Case(**base)


def _diagnose(case, tmp_path, greedy=True):
    path = tmp_path / f"case_{case.seed}"
    write_bag(case, path)
    plant, desc, ds = workbench.load(path)
    model = workbench.build_model(plant, desc)
    return ds, model, workbench.diagnose(ds, model, plant.candidates(desc), greedy_mode=greedy).to_json()


def test_coulomb_level_with_derived_velocity_and_40_percent_rest(tmp_path):
    case = _case(1, ("joint_coulomb_friction",), _truth(Fc=4.0))
    _, _, out = _diagnose(case, tmp_path)
    assert [g["added"] for g in out["greedy"][1:]] == ["joint_coulomb_friction"]
    fin = out["final"]["params"]
    assert fin["Fc"] == pytest.approx(4.0, rel=0.03)
    assert fin["Fv"] == pytest.approx(12.0, rel=0.05)   # viscous does not absorb Coulomb


def test_6ms_delay_found_with_its_uncertainty(tmp_path):
    case = _case(2, ("time_delay",), _truth(tau=0.006), profile="chirp", ar=0.0)
    _, _, out = _diagnose(case, tmp_path)
    assert [g["added"] for g in out["greedy"][1:]] == ["time_delay"]
    tau, se = out["final"]["params"]["tau"], out["final"]["stderr"]["tau"]
    assert 0 < se < 5e-4
    assert abs(tau - 0.006) < max(4 * se, 3e-4)


def test_two_hidden_effects_greedy_recovers_both_values(tmp_path):
    case = _case(3, ("joint_coulomb_friction", "torque_sensor_offset"), _truth(Fc=3.0, OF=-2.0))
    _, _, out = _diagnose(case, tmp_path)
    assert sorted(g["added"] for g in out["greedy"][1:]) == ["joint_coulomb_friction",
                                                               "torque_sensor_offset"]
    fin = out["final"]["params"]
    assert fin["Fc"] == pytest.approx(3.0, rel=0.05)
    assert fin["OF"] == pytest.approx(-2.0, rel=0.05)
    assert fin["Fv"] == pytest.approx(12.0, rel=0.05)


@pytest.mark.parametrize("flavour,truth", [("linear", _truth()),
                                           ("pendulum", _truth(M=0.4, Fv=0.2, mc=0.3))])
def test_control_nothing_significant_and_residual_white(tmp_path, flavour, truth):
    case = _case(4, (), truth, flavour=flavour, vmax=0.5 if flavour == "linear" else 2.0,
                 quantum=2e-6 if flavour == "linear" else 2 * np.pi / 2**16, ar=0.0)
    ds, model, out = _diagnose(case, tmp_path)
    assert not any(r["significant"] for r in out["ranking"]), [(r["effect"], r["p_value"])
                                                                for r in out["ranking"]]
    assert len(out["greedy"]) == 1
    # the whiteness test is valid on the filtered data: the right model is called white
    cmp = workbench.compare(ds, model)
    assert cmp.whiteness["joint"]["decimate"] > 1
    assert cmp.whiteness["joint"]["white"]


# ----------------------------------------------------------------------------- bad input

PRISMATIC = "plant: axis\naxis:\n  joint_type: prismatic\n  inertia: 2.0\n"


def _arrays(n=4000, fs=1000.0, seed=0):
    rng = np.random.default_rng(seed)
    t = np.arange(n) / fs
    q = 0.1 * np.sin(2 * np.pi * 0.7 * t)
    qdd = -(2 * np.pi * 0.7) ** 2 * q
    eff = 2.0 * qdd + 5.0 * np.gradient(q, t) + rng.normal(0, 0.05, n)
    return t, q, eff


def _diag_arrays(t, q, eff):
    from cablelab.description import load_description
    from cablelab.plants import get_plant
    from cablelab.plants.axis.dataset import dataset_from_arrays

    desc = load_description(PRISMATIC)
    plant = get_plant("axis")
    ds = dataset_from_arrays(t, q, eff, desc, source="run.mcap")
    return workbench.diagnose(ds, workbench.build_model(plant, desc), plant.candidates(desc))


@pytest.mark.parametrize("problem,words", [
    ("short", ["samples", "longer"]),
    ("still", ["moves in only", "record moves"]),
    ("constant", ["constant", "record the measured effort"]),
    ("nan_run", ["NaN", "gap"]),
    ("backwards", ["not monotonic", "clock"]),
])
def test_bad_input_one_line_message_naming_problem_and_fix(problem, words):
    t, q, eff = _arrays()
    if problem == "short":
        t, q, eff = t[:300], q[:300], eff[:300]
    elif problem == "still":
        # held still: the encoder only toggles between two counts
        q = 0.05 + 1e-5 * (np.random.default_rng(1).random(q.size) < 0.3)
    elif problem == "constant":
        eff = np.full_like(eff, 1.5)
    elif problem == "nan_run":
        eff = eff.copy()
        eff[1000:1500] = np.nan
    elif problem == "backwards":
        t = t.copy()
        t[2000:] -= 0.5
    with pytest.raises(CablelabError) as exc:
        _diag_arrays(t, q, eff)
    msg = str(exc.value)
    assert "\n" not in msg
    for w in words:
        assert w in msg, msg


def test_stribeck_effect_recovers_breakaway_level_and_speed(tmp_path):
    """Truth: tanh-smoothed Stribeck law F_c + (F_s - F_c) exp(-(v / v_s)^2); the model
    inertia + viscous + Coulomb + joint_stribeck_friction recovers F_s = F_c + dFs and v_s."""
    from cablelab.fit import identify

    case = _case(5, ("joint_coulomb_friction",), _truth(Fc=3.0, Fs=6.0, vs=0.08), ar=0.0,
                 noise_rel=0.01)
    path = tmp_path / "stribeck"
    write_bag(case, path)
    plant, desc, ds = workbench.load(path)
    model = workbench.build_model(plant, desc, ["joint_coulomb_friction", "joint_stribeck_friction"])
    r = identify(model, ds)
    assert r.params["Fc"] + r.params["dFs"] == pytest.approx(6.0, rel=0.10)
    assert r.params["Fc"] == pytest.approx(3.0, rel=0.10)
    assert r.params["vs_rel"] * np.percentile(np.abs(ds.act_vel[:, 0]), 99) == pytest.approx(0.08, rel=0.25)
    # the contract's parameters F_s, v_s reported beside the fitted dFs, vs_rel
    own = r.effect_params("joint_stribeck_friction", ds)
    assert own["F_s"] == pytest.approx(r.params["Fc"] + r.params["dFs"], rel=1e-12)
    assert own["F_s"] == pytest.approx(6.0, rel=0.10) and own["v_s"] == pytest.approx(0.08, rel=0.25)
    # and without it the Coulomb-only model leaves a clearly larger error
    r0 = identify(workbench.build_model(plant, desc, ["joint_coulomb_friction"]), ds)
    assert r.linear.rss < 0.7 * r0.linear.rss


def test_slow_slew_axis_under_chirps_coulomb_and_inertia_with_parallel_filtering(tmp_path):
    """A crane slew axis as one drive: 250 kg m^2, 100 Hz, 1-3 Hz chirp bursts, 2^17-count
    encoder, no recorded velocity, 30 % rest. The encoder forces a cut-off of a few Hz, inside
    the chirp's band: filtering only the positions attenuates the acceleration and sharpens the
    Coulomb column where the effort is not filtered, and the least squares moves the missing
    inertia force into friction (Coulomb some 20 % low on this case). The parallel filter (the
    same low-pass on the effort and every regressor column, IDIM-LS) restores Coulomb within
    5 % and the inertia within 2 %. Truth: solve_ivp with a tanh Coulomb band (diagnosis_cases)."""
    from cablelab.conditioning import Conditioning
    from cablelab.fit import identify

    truth = _truth(M=250.0, Fv=120.0, Fc=40.0, eps=0.0015, vs=0.03)
    case = _case(6, ("joint_coulomb_friction",), truth, flavour="slew", fs=100.0, duration=36.0,
                 profile="chirp", rest_fraction=0.3, quantum=2 * np.pi / 2**17, vmax=0.3,
                 noise_rel=0.02, ar=0.5)
    ds, _, out = _diagnose(case, tmp_path)
    assert ds.parallel_hz is not None and ds.parallel_hz < 10.0    # below the default fs / 10
    assert [g["added"] for g in out["greedy"][1:]] == ["joint_coulomb_friction"]
    fin = out["final"]["params"]
    assert fin["Fc"] == pytest.approx(40.0, rel=0.05)
    assert fin["M"] == pytest.approx(250.0, rel=0.02)
    # the whiteness test stays valid on parallel-filtered data: the right model is called white
    plant, desc, _ = workbench.load(tmp_path / f"case_{case.seed}")
    cmp = workbench.compare(ds, workbench.build_model(plant, desc, ["joint_coulomb_friction"]))
    assert cmp.whiteness["joint"]["decimate"] > 1 and cmp.whiteness["joint"]["white"]
    # the same bag with the positions filtered alone: biased (the failure this fixes)
    plant, desc, ds_old = workbench.load(tmp_path / f"case_{case.seed}",
                                         options={"conditioning": Conditioning(parallel=False)})
    assert ds_old.parallel_hz is None
    old = identify(workbench.build_model(plant, desc, ["joint_coulomb_friction"]), ds_old).params
    assert abs(old["Fc"] / 40.0 - 1) > 2 * abs(fin["Fc"] / 40.0 - 1)
    assert abs(old["Fc"] / 40.0 - 1) > 0.08


def test_parallel_filter_is_exact_on_subsets_with_cuts():
    """Oracle: linearity. y = M qdd + Fv qd + Fc sign(qd) sample by sample; low-passing y on the
    whole record and the regressor on a subset with a cut (a cross-validation training set)
    gives the same equation away from the segment edges, which Dataset.subset marks invalid:
    the fit returns the parameters to 5e-4 although sign(qd) is a sharp step and the filter
    (3 Hz at 100 Hz) smooths it over ~30 samples."""
    from cablelab.conditioning import lowpass
    from cablelab.dataset import Dataset
    from cablelab.fit import identify
    from cablelab.model import Model

    fs, n = 100.0, 6000
    t = np.arange(n) / fs
    qd = 0.3 * np.sin(2 * np.pi * 0.4 * t) * np.sin(2 * np.pi * 0.05 * t + 0.3)
    qdd = np.gradient(qd, 1 / fs)
    y = 50.0 * qdd + 20.0 * qd + 7.0 * np.sign(qd)
    ds = Dataset(plant="axis", t=t, y=lowpass(y, fs, 3.0)[:, None], channels=("joint",),
                 signals={"q": np.cumsum(qd) / fs, "qd": qd, "qdd": qdd}, actuators=("joint",),
                 act_vel=qd[:, None], parallel_hz=3.0)
    model = Model("axis", ("axis_inertia", "joint_viscous_friction", "joint_coulomb_friction"))
    keep = np.r_[0:2000, 2600:6000]                  # a training set around a cut-out test block
    sub = ds.subset(keep)
    assert not sub.valid[1990:2010].any() and sub.valid[2100:2400].all()   # edges settle
    p = identify(model, sub).params
    assert p["M"] == pytest.approx(50.0, rel=5e-4)
    assert p["Fv"] == pytest.approx(20.0, rel=5e-4)
    assert p["Fc"] == pytest.approx(7.0, rel=5e-4)
    # without the parallel filter on the columns the same data are biased
    q = identify(model, sub.replace(parallel_hz=None)).params
    assert abs(q["Fc"] / 7.0 - 1) > 0.05 and abs(q["Fv"] / 20.0 - 1) > 0.1
