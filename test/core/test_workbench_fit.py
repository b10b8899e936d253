"""Workbench core: effect registry, linear LS (rank, base parameters, bounds, uncertainty),
separable LS for a delay, conditioning. Oracles: closed forms, Monte Carlo scatter, exact sums."""
import numpy as np
import pytest

from cablelab.conditioning import derivatives, is_uniform, lowpass, uniform_grid, unwrap_angle
from cablelab.description import load_description
from cablelab.effects import effects_for, get_effect
from cablelab.errors import CablelabError
from cablelab.fit import identify, solve_linear
from cablelab.dataset import Dataset
from cablelab.effects.base import Param
from cablelab.model import Model
from cablelab.plants import get_plant

PRISMATIC = load_description("plant: axis\naxis:\n  joint_type: prismatic\n")


def test_registry_lists_catalog_effects_and_rejects_bad_ids():
    axis = effects_for("axis")
    for eid in ("joint_viscous_friction", "joint_coulomb_friction", "torque_sensor_offset", "time_delay"):
        assert eid in axis
    with pytest.raises(CablelabError, match=r"unknown effect 'bogus'.*joint_coulomb_friction"):
        get_effect("bogus", "axis")
    with pytest.raises(CablelabError, match=r"does not apply to plant cdpr.*valid effects for cdpr"):
        get_effect("axis_inertia", "cdpr")
    with pytest.raises(CablelabError, match="has no workbench model"):
        get_plant("nonexistent_plant")


def test_linear_fit_stderr_matches_monte_carlo_scatter():
    rng = np.random.default_rng(0)
    n = 400
    phi = np.stack([rng.normal(size=n), np.sin(np.linspace(0, 20, n)), np.ones(n)], axis=1)
    theta = np.array([2.0, -1.5, 0.3])
    params = [Param(k, "-") for k in ("a", "b", "c")]
    est, se = [], []
    for _ in range(300):
        y = phi @ theta + 0.5 * rng.normal(size=n)
        f = solve_linear(phi, y, params)
        est.append(f.theta)
        se.append(f.stderr)
    est, se = np.array(est), np.array(se)
    assert np.allclose(est.mean(axis=0), theta, atol=4 * se.mean(axis=0) / np.sqrt(300))
    # LS covariance sigma^2 (Phi^T Phi)^-1 predicts the scatter of the estimates
    assert np.allclose(est.std(axis=0), se.mean(axis=0), rtol=0.15)
    assert f.rank == 3 and f.cond < 10


def test_rank_deficient_fit_names_the_direction_or_regroups_base_parameters():
    rng = np.random.default_rng(1)
    x = rng.normal(size=300)
    phi = np.stack([x, 2.0 * x, rng.normal(size=300)], axis=1)  # b column = 2 a column
    y = phi @ np.array([1.0, 0.5, 3.0])
    params = [Param("a", "-"), Param("b", "-"), Param("c", "-")]
    with pytest.raises(CablelabError, match=r"rank-deficient fit \(rank 2 of 3.*a.*b.*--fix") as ei:
        solve_linear(phi, y, params)
    assert "\n" not in str(ei.value)
    f = solve_linear(phi, y, params, on_deficient="base")
    assert f.rank == 2 and len(f.unidentifiable) == 1
    # the identifiable combination a + 2 b (exact sum 1 + 2 * 0.5 = 2) or b + 0.5 a (= 1)
    vals = f.params
    combo = [k for k in vals if "a" in k and "b" in k][0]
    expect = 2.0 if combo.startswith("a") else 1.0
    assert vals[combo] == pytest.approx(expect, rel=1e-9)
    assert vals["c"] == pytest.approx(3.0, rel=1e-9)


def test_bounded_least_squares_keeps_physical_sign():
    rng = np.random.default_rng(2)
    x1, x2 = rng.normal(size=500), rng.normal(size=500)
    y = 1.0 * x1 - 0.2 * x2 + 0.01 * rng.normal(size=500)
    f = solve_linear(np.stack([x1, x2], 1), y, [Param("a", "-"), Param("F", "-", lower=0.0)])
    assert f.params["F"] == pytest.approx(0.0, abs=1e-12)
    assert f.active_bounds == ["F"]
    free = solve_linear(np.stack([x1, x2], 1), y, [Param("a", "-"), Param("F", "-")])
    assert free.params["F"] == pytest.approx(-0.2, abs=0.01)


def _axis_data(t, q, f, **kw):
    from cablelab.plants.axis.dataset import dataset_from_arrays

    return dataset_from_arrays(t, q, f, PRISMATIC, kw.get("options"))


def test_separable_ls_recovers_time_delay_and_linear_params():
    fs = 500.0
    t = np.arange(0, 20, 1 / fs)
    q = 0.3 * np.sin(1.3 * t) + 0.1 * np.sin(4.1 * t + 1)
    qd = 0.3 * 1.3 * np.cos(1.3 * t) + 0.1 * 4.1 * np.cos(4.1 * t + 1)
    qdd = -0.3 * 1.69 * np.sin(1.3 * t) - 0.1 * 4.1**2 * np.sin(4.1 * t + 1)
    force = 12.0 * qdd + 30.0 * qd + 4.0 * np.sign(qd)
    tau = 0.012  # measurement lags the model by 12 ms
    meas = np.interp(t - tau, t, force)
    ds = _axis_data(t, q, meas)
    r = identify(Model("axis", ("axis_inertia", "joint_viscous_friction", "joint_coulomb_friction",
                                "time_delay")), ds)
    assert r.params["tau"] == pytest.approx(tau, abs=0.0005)
    assert r.params["M"] == pytest.approx(12.0, rel=0.02)
    assert r.params["Fv"] == pytest.approx(30.0, rel=0.02)
    assert r.params["Fc"] == pytest.approx(4.0, rel=0.05)
    assert r.stderr["tau"] > 0


def test_known_parameters_move_to_the_left_hand_side():
    fs = 200.0
    t = np.arange(0, 10, 1 / fs)
    q = np.sin(t)
    force = 5.0 * -np.sin(t) + 2.0 * np.cos(t)
    ds = _axis_data(t, q, force)
    r = identify(Model("axis", ("axis_inertia", "joint_viscous_friction"), fixed={"M": 5.0}), ds)
    assert r.params["Fv"] == pytest.approx(2.0, rel=1e-3)
    assert r.stderr["M"] == 0.0 and "M" in r.fixed
    with pytest.raises(CablelabError, match="fixed parameter 'X'"):
        identify(Model("axis", ("axis_inertia",), fixed={"X": 1.0}), ds)


def test_a_linear_fit_builds_its_regressor_once_and_predicts_from_it(monkeypatch):
    """One evaluation per fit: the model's regressor is built once and the fitted output is that
    regressor times the parameters (closed form: noise-free data, exact parameters)."""
    fs = 200.0
    t = np.arange(0, 10, 1 / fs)
    q = np.sin(t) + 0.3 * np.sin(3.1 * t)
    qd, qdd = np.cos(t) + 0.93 * np.cos(3.1 * t), -np.sin(t) - 2.883 * np.sin(3.1 * t)
    ds = _axis_data(t, q, 5.0 * qdd + 2.0 * qd)
    model = Model("axis", ("axis_inertia", "joint_viscous_friction"))
    builds = []
    real = Model.regressor

    def counted(self, data):
        builds.append(data)
        return real(self, data)

    monkeypatch.setattr(Model, "regressor", counted)
    monkeypatch.setattr(Model, "predict", lambda *a: pytest.fail("the fit rebuilt its prediction"))
    r = identify(model, ds)
    assert len(builds) == 1
    assert r.params["M"] == pytest.approx(5.0, rel=1e-3) and r.params["Fv"] == pytest.approx(2.0, rel=1e-3)
    ev = model.evaluate(ds, {})
    ok = r.valid
    assert np.allclose(r.y_hat[ok], ev.phi[ok] @ [r.params[c.name] for c in ev.columns])


def test_conditioning_derivatives_unwrap_and_irregular_times():
    fs = 1000.0
    t = np.arange(0, 5, 1 / fs)
    x = np.sin(2 * np.pi * 1.0 * t)
    xf, xd, xdd = derivatives(x, fs, 50.0)
    inner = slice(100, -100)
    w = 2 * np.pi
    assert np.max(np.abs(xd[inner] - w * np.cos(w * t[inner]))) < 1e-3 * w
    assert np.max(np.abs(xdd[inner] + w**2 * np.sin(w * t[inner]))) < 1e-3 * w**2
    # zero phase: a filtered sine keeps its phase
    assert np.max(np.abs(lowpass(x, fs, 50.0)[inner] - x[inner])) < 1e-4
    wrapped = np.angle(np.exp(1j * 3 * t))
    assert np.allclose(unwrap_angle(wrapped), 3 * t, atol=1e-9)
    rng = np.random.default_rng(3)
    ti = np.sort(rng.uniform(0, 5, 3000))
    assert not is_uniform(ti)
    tu, (xu,) = uniform_grid(ti, np.sin(ti))
    assert is_uniform(tu) and np.max(np.abs(xu - np.sin(tu))) < 1e-3
    with pytest.raises(CablelabError, match="only 20 samples"):
        _axis_data(t[:20], x[:20], x[:20])


def test_model_regressor_is_sum_of_effect_blocks_on_a_multi_actuator_map():
    """Generic per-actuator effects through an actuator -> channel map (CDPR-like, C=2, n_act=3)."""
    rng = np.random.default_rng(4)
    n = 50
    amap = rng.normal(size=(n, 2, 3))
    v = rng.normal(size=(n, 3))
    ds = Dataset(plant="axis", t=np.arange(n) * 0.01, y=np.zeros((n, 2)), channels=("a", "b"),
                 actuators=("m1", "m2", "m3"), act_vel=v, act_map=amap)
    eff = get_effect("joint_coulomb_friction")
    names = [p.name for p in eff.columns(ds)]
    assert names == ["Fc[m1]", "Fc[m2]", "Fc[m3]"]
    fc = np.array([1.0, 2.0, 3.0])
    expect = np.einsum("nca,na->nc", amap, np.sign(v) * fc)
    assert np.allclose(eff.block(ds) @ fc, expect)


def test_unexcited_columns_holds_zero_then_the_later_of_a_dependent_pair():
    from cablelab.fit.linear import unexcited_columns

    rng = np.random.default_rng(5)
    x = rng.normal(size=(400, 3))
    ps = [Param(n, "1") for n in "abcd"]
    y = x @ np.array([1.0, 2.0, 3.0])
    # full rank: nothing held
    assert unexcited_columns(x, y, ps[:3]) == []
    # a zero column is held
    phi = np.column_stack([x[:, 0], np.zeros(400), x[:, 1], x[:, 2]])
    assert unexcited_columns(phi, y, ps) == [1]
    # two identical columns (up to scale): the later one is held, the rest has full rank
    phi = np.column_stack([x[:, 0], x[:, 1], 3.0 * x[:, 1], x[:, 2]])
    held = unexcited_columns(phi, y, ps)
    assert held == [2]
    keep = [i for i in range(4) if i not in held]
    assert np.linalg.matrix_rank(phi[:, keep]) == len(keep)
    # a combination of three columns: one of them is held
    phi = np.column_stack([x, x[:, 0] - 0.5 * x[:, 2]])
    held = unexcited_columns(phi, y, ps)
    assert len(held) == 1 and held[0] in (0, 2, 3)


def test_identify_holds_unexcited_parameters_at_their_nominal_and_fits_the_rest():
    from cablelab.effects import register
    from cablelab.effects.base import Effect
    from cablelab.fit import identify
    from cablelab.fit.linear import RankDeficient
    from cablelab.dataset import Dataset
    from cablelab.model import Model

    plant = "toy_unexcited"
    sig = lambda name: (lambda ds: ds.require_signal(name).reshape(ds.n, 1, 1))  # noqa: E731
    register(Effect(id="toy_u_base", plants=(plant,), params=(Param("a", "N", 0.0),),
                    explanation="t", signature="t", reference="test", regressor=sig("u")))
    register(Effect(id="toy_u_idle", plants=(plant,), params=(Param("b", "N", 7.5),),
                    explanation="t", signature="t", reference="test", regressor=sig("z")))
    t = np.arange(0, 10, 0.01)
    u = np.sin(t)
    rng = np.random.default_rng(3)
    ds = Dataset(plant=plant, t=t, y=(2.0 * u + 0.01 * rng.normal(size=t.size))[:, None],
                 channels=("f",), signals={"u": u, "z": np.zeros_like(t)})
    with pytest.raises(RankDeficient, match="b"):
        identify(Model(plant, ("toy_u_base", "toy_u_idle")), ds)
    r = identify(Model(plant, ("toy_u_base", "toy_u_idle"), unexcited="hold"), ds)
    assert r.held == {"b": 7.5} and r.params["b"] == 7.5 and "b" in r.fixed
    assert r.params["a"] == pytest.approx(2.0, abs=0.01)
    assert "b = 7.5 N" in r.held_warning() and "--strict" in r.held_warning()
    ref = identify(Model(plant, ("toy_u_base",)), ds)
    assert r.params["a"] == pytest.approx(ref.params["a"], rel=1e-12)


def test_a_model_whose_every_parameter_is_unexcited_is_held_whole():
    from cablelab.fit.linear import unexcited_columns

    phi = np.zeros((300, 1, 2))
    y = np.random.default_rng(2).normal(size=300)
    ps = [Param("a", "1", 1.5), Param("b", "1", -2.0)]
    assert unexcited_columns(phi, y, ps) == [0, 1]
    f = solve_linear(phi[:, :, :0], y, [])               # nothing left to fit: the residual is y
    assert f.rss == pytest.approx(float(y @ y))
