"""Diagnosis building blocks against closed forms: metrics, folds, worst segments, regimes,
whiteness/cross-correlation bands; and the simulation-based fit (free-run, both objectives)."""
import numpy as np
import pytest

from cablelab.description import load_description
from cablelab.diagnose import (channel_metrics, derived_regimes, fold_indices, residual_by_regime,
                               whiteness, worst_segments)
from cablelab.errors import CablelabError
from cablelab.fit.simulation import objective_residual
from cablelab.dataset import Dataset

T = np.arange(0, 10, 0.001)


def test_metrics_closed_forms():
    y = np.sin(2 * np.pi * T)[:, None]
    m = channel_metrics(y, y + 0.1 * np.cos(2 * np.pi * T)[:, None])[0]
    assert m["nrmse"] == pytest.approx(0.1, rel=1e-3)  # rms(0.1 cos) / rms(sin)
    assert m["fit_percent"] == pytest.approx(90.0, rel=1e-3)
    assert m["nmse"] == pytest.approx(0.01, rel=1e-3)
    assert m["mae"] == pytest.approx(0.1 * 2 / np.pi, rel=1e-3)  # mean |cos| = 2/pi
    assert m["mre"] == pytest.approx(0.1, rel=1e-3)  # sum|0.1 cos| / sum|sin|
    assert m["max_abs"] == pytest.approx(0.1, rel=1e-6)
    assert channel_metrics(y, 2 * y + 3)[0]["pearson"] == pytest.approx(1.0, abs=1e-12)
    assert channel_metrics(y, np.full_like(y, y.mean()))[0]["fit_percent"] == pytest.approx(0.0, abs=1e-9)


def test_objectives_are_nmse_and_one_minus_pearson():
    rng = np.random.default_rng(0)
    y = rng.normal(size=(500, 2))
    ys = 0.7 * y + 0.3 * rng.normal(size=(500, 2)) + 5.0
    r = objective_residual(y, ys, "nmse")
    j = sum(np.sum((y[:, c] - ys[:, c]) ** 2) / np.sum((y[:, c] - y[:, c].mean()) ** 2) for c in range(2))
    assert r @ r == pytest.approx(j, rel=1e-12)  # 003 eq. 28
    rho = np.mean([np.corrcoef(y[:, c], ys[:, c])[0, 1] for c in range(2)])
    r = objective_residual(y, ys, "pearson")
    assert 1 - r @ r == pytest.approx(rho, rel=1e-12)  # 000 eq. 7
    with pytest.raises(CablelabError, match="unknown objective"):
        objective_residual(y, ys, "mse")


def test_blocked_folds_are_contiguous_disjoint_and_guarded():
    folds = fold_indices(1000, 5, guard=10)
    tests = np.concatenate([te for _, te in folds])
    assert np.array_equal(np.sort(tests), np.arange(1000))
    for train, test in folds:
        assert np.all(np.diff(test) == 1)
        assert not set(train) & set(test)
        assert np.min(np.abs(train[:, None] - test[None, :])) > 10
    with pytest.raises(CablelabError, match="only 100 samples for 5 folds"):
        fold_indices(100, 5)


def test_worst_segment_finds_the_burst():
    res = 0.01 * np.random.default_rng(1).normal(size=(T.size, 1))
    res[(T > 4.0) & (T < 4.2)] += 1.0
    segs = worst_segments(T, res, np.ones_like(res), ("c",), window_s=0.2)
    assert segs[0]["t_start"] == pytest.approx(4.0, abs=0.01) and segs[0]["t_end"] == pytest.approx(4.2, abs=0.01)
    assert segs[0]["error"] == pytest.approx(1.0, rel=0.01)
    assert all(s["t_start"] >= segs[0]["t_end"] or s["t_end"] <= segs[0]["t_start"] for s in segs[1:])


def test_regimes_localise_a_coulomb_like_residual():
    v = np.sin(2 * np.pi * 0.5 * T)
    ds = Dataset(plant="axis", t=T, y=np.ones((T.size, 1)), channels=("joint",), act_vel=v[:, None])
    res = (0.5 * np.sign(v))[:, None]
    rows = residual_by_regime(res, np.ones_like(res), derived_regimes(ds), ("joint",))
    by = {(r["regime"], r["label"]): r for r in rows}
    assert by[("velocity", "moving +")]["mean"] == pytest.approx(0.5)
    assert by[("velocity", "moving -")]["mean"] == pytest.approx(-0.5)
    # reversals happen every second: within +-50 ms of them about 10 % of the time
    near = by[("reversal", "near reversal")]["n"] / T.size
    assert near == pytest.approx(0.1, abs=0.01)


def test_whiteness_band_and_cross_correlation_lag():
    rng = np.random.default_rng(2)
    e = rng.normal(size=20000)
    w = whiteness(e, {"u": e})
    assert w["band"] == pytest.approx(2.576 / np.sqrt(20000))
    assert w["white"]
    ar = np.empty_like(e)
    ar[0] = e[0]
    for k in range(1, e.size):  # AR(1) test signal (building the oracle, not a batch path)
        ar[k] = 0.9 * ar[k - 1] + e[k]
    w = whiteness(ar)
    assert not w["white"] and w["autocorr"][1] == pytest.approx(0.9, abs=0.02)
    u = rng.normal(size=20000)
    res = np.roll(u, 3)  # residual = input 3 samples earlier
    xc = whiteness(res, {"u": u})["cross"]["u"]
    lag = xc["lags"][int(np.argmax(np.abs(xc["xcorr"])))]
    assert lag == 3 and not xc["uncorrelated"]


def test_simulation_fit_recovers_axis_parameters_with_both_objectives():
    from cablelab.plants.axis.dataset import dataset_from_arrays
    from cablelab.plants.axis.freerun import fit_free_run
    from cablelab.plants.axis.sim import AxisTruth
    from cablelab.plants.axis.truth import simulate_axis

    desc = load_description("plant: axis\naxis:\n  joint_type: prismatic\n")
    run = simulate_axis(desc, AxisTruth(inertia=2.0, viscous=5.0, coulomb=1.0), duration=6.0,
                        fs=500.0, amplitude=0.3, noise_position=1e-5, seed=1)
    ds = dataset_from_arrays(run.t, run.q, run.effort, desc)
    for obj in ("nmse", "pearson"):
        f = fit_free_run(ds, {"M": 1.4, "Fv": 7.0, "Fc": 0.6}, objective=obj, max_iter=20)
        assert f.params["M"] == pytest.approx(2.0, rel=0.03), obj
        assert f.params["Fv"] == pytest.approx(5.0, rel=0.05), obj
        assert f.params["Fc"] == pytest.approx(1.0, rel=0.05), obj
        truth = {"M": 2.0, "Fv": 5.0, "Fc": 1.0}
        for k, v in truth.items():  # the (autocorrelation-corrected) errors cover the truth
            assert 0 < f.stderr[k] < 0.05 * v and abs(f.params[k] - v) < 3 * f.stderr[k], (obj, k)
        assert f.nmse < 1e-3 and f.pearson > 0.999


def test_typed_diagnosis_is_the_ranking_once_reshaped():
    """``workbench.diagnose`` returns a :class:`Diagnosis` whose JSON carries every ranking row's
    documented fields unchanged (second path: ``rank_candidates`` called directly), and whose
    greedy steps end at the best significant model."""
    from cablelab.diagnose import rank_candidates
    from cablelab.diagnose.result import ROW_KEYS, Diagnosis
    from cablelab.model import Model
    from cablelab.plants.axis.dataset import dataset_from_arrays
    from cablelab.workbench import diagnose

    rng = np.random.default_rng(1)
    t = np.arange(0, 20, 0.005)
    q = 0.2 * np.sin(2 * np.pi * 0.5 * t) + 0.05 * np.sin(2 * np.pi * 1.7 * t)
    qd = np.gradient(q, t)
    qdd = np.gradient(qd, t)
    force = 2.0 * qdd + 5.0 * qd + 1.5 * np.tanh(qd / 1e-3) + 0.05 * rng.normal(size=t.size)
    desc = load_description("plant: axis\naxis: {joint_type: prismatic}\n")
    ds = dataset_from_arrays(t, q, force, desc, qd=qd)
    model = Model("axis", ("axis_inertia", "joint_viscous_friction"))
    cands = ("joint_coulomb_friction", "torque_sensor_offset")
    d = diagnose(ds, model, cands, folds=4)
    assert isinstance(d, Diagnosis) and d.final is None
    rows = rank_candidates(model, ds, cands, folds=4).ranking
    js = d.to_json()
    assert [r["effect"] for r in js["ranking"]] == [r.effect for r in rows]
    for got, row in zip(js["ranking"], rows):      # every field set is in the JSON, in order
        assert list(got) == [k for k in ROW_KEYS if getattr(row, k) is not None
                             or k in ("error_before", "error_after")]
        assert got == {k: getattr(row, k) for k in got}
    assert d.ranking[0].effect == "joint_coulomb_friction" and d.ranking[0].significant
    g = diagnose(ds, model, cands, folds=4, greedy_mode=True)
    assert g.final.effects[-1] == "joint_coulomb_friction" and g.to_json()["final"]["error"] == g.final.error
    assert g.lines()[0].startswith("plant axis: model axis_inertia + joint_viscous_friction")


def test_practical_gain_counts_only_the_channels_a_candidate_changes():
    """Closed form: the candidate changes channel 0 only; the practical gain is channel 0's own
    relative NRMSE drop (not the geometric-mean drop over both, which is diluted to its square
    root), a round-off change (1e-9 x rms) does not count as a change, a real one does."""
    from cablelab.diagnose.score import changed_channels, channel_nrmse, heldout_error, practical_gain

    rng = np.random.default_rng(4)
    n = 2000
    s = np.sin(np.linspace(0, 20, n))
    y = np.column_stack([s + 0.1 * rng.standard_normal(n), 0.1 * rng.standard_normal(n)])
    y0 = np.column_stack([0.7 * s, np.zeros(n)])            # misses 30 % of channel 0
    y1 = np.column_stack([s, np.zeros(n)])                  # the candidate explains it
    c0, c1 = channel_nrmse(y, y0), channel_nrmse(y, y1)
    gain, changed = practical_gain(y, y0, y, y1)
    assert changed.tolist() == [True, False]
    assert gain == pytest.approx(1 - c1[0] / c0[0], rel=1e-12)
    diluted = 1 - heldout_error(y, y1) / heldout_error(y, y0)
    assert diluted == pytest.approx(1 - np.sqrt(c1[0] / c0[0]), rel=1e-12) and diluted < gain
    y1r = y1.copy()
    y1r[:, 1] += 1e-9 * np.sqrt(np.mean(y[:, 1] ** 2))
    assert changed_channels(y, y0, y1r).tolist() == [True, False]
    y1c = y1.copy()
    y1c[:, 1] += 0.05 * np.sqrt(np.mean(y[:, 1] ** 2))     # a real change on channel 1
    gain_c, changed_c = practical_gain(y, y0, y, y1c)
    assert changed_c.tolist() == [True, True]
    assert gain_c == pytest.approx(1 - heldout_error(y, y1c) / heldout_error(y, y0), rel=1e-12)
    assert practical_gain(y, y0, y, y0)[0] == 0.0           # changes nothing: no gain
