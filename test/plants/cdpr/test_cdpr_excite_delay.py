"""``cablelab excite --params tau,...`` on the CDPR, whose ``remeasure`` hook re-forms the wrench
from the measured tensions at the delayed pose: the delay's column is the sensitivity of the
residual the fit sees to tau (:class:`cablelab.excite.Linearised`), not minus the time derivative
of the model output.

Oracles: (1) bench/cases_cdpr.py (its own structure matrix and tension distribution, none of the
fitting code) records the same motion twice, with the dynamometers reading the truth of t and of
t - delta: the change of the fitted residual between the two recordings is delta x the column;
(2) for the design's own dataset (the controller's feedforward tensions of the described
platform), the same with the plant's feedforward tensions evaluated on the motion at t - delta;
(3) the MuJoCo CAROCA (plants/cdpr/sim.py) tracks the designed reference with every cable taut."""
import dataclasses
import json
import os
import sys

import numpy as np
import pytest

from cablelab import excite as E
from cablelab import workbench
from cablelab.cli import main
from cablelab.model import Model
from cablelab.plants.cdpr.control import PdffConfig
from cablelab.plants.cdpr.dataset import CdprArrays, dataset_from_arrays
from cablelab.plants.cdpr.excite import motion_dataset
from cablelab.plants.cdpr.sim import CdprTruth, default_description, default_description_path, simulate
from cablelab.plants.cdpr.topics import REFERENCE
from cablelab.plants.cdpr.trajectory import Trajectory

sys.path.insert(0, os.path.join(os.path.dirname(__file__), "..", "..", "..", "bench"))
import cases_cdpr  # noqa: E402


def _sines(t, centre=(0.0, 0.0, 0.85), amp=(0.3, 0.15, 0.1), hz=(0.2, 0.27, 0.33), phase=(0.0, 1.0, 2.0)):
    w = 2 * np.pi * np.asarray(hz)
    arg = w * np.asarray(t, float)[:, None] + np.asarray(phase)
    a = np.asarray(amp)
    return np.asarray(centre) + a * np.sin(arg), a * w * np.cos(arg), -a * w * w * np.sin(arg)


def _rel_errors(change, pred):
    return [np.sqrt(np.mean((change[:, c] - pred[:, c]) ** 2)) / np.sqrt(np.mean(change[:, c] ** 2))
            for c in range(change.shape[1])]


def test_tau_column_is_the_residual_change_of_a_simulated_delay(tmp_path):
    case = cases_cdpr.draw_designed_case(7000, "pair")        # hidden dynamometer offsets, 200 Hz
    tr = case.truth
    tr.update(com=np.zeros(3), duration=20.0, noise_rel=np.full(8, 1e-7), outlier_rate=0.0,
              reference=lambda t: _sines(np.atleast_1d(t)))
    delta = 0.002                                              # below the sample period (5 ms)
    ds = {}
    for tau in (0.0, delta):
        tr["tau"] = tau
        cases_cdpr.write_bag(case, tmp_path / f"tau_{tau}")
        plant, desc, ds[tau] = workbench.load(tmp_path / f"tau_{tau}", None, dict(case.options))
    model = workbench.build_model(plant, desc, case.effects + ("tension_sensor_offset", "time_delay"),
                                  fixed=case.fixed)
    m = tr["m"]
    theta = {"m": m, "mx": 0.0, "my": 0.0, "m_a": m, "mx_a": 0.0, "my_a": 0.0, "mz_a": 0.0,
             **{f"b[{n}]": v for n, v in zip(cases_cdpr.WINCHES, tr["b"])}}
    lin = E.Linearised(model, theta)
    col = lin.tau_column(ds[0.0])
    r0, ok0 = lin.residual(ds[0.0], 0.0)
    r1, ok1 = lin.residual(ds[delta], 0.0)
    ok = ok0 & ok1 & np.isfinite(col).all(axis=1)
    assert ok.sum() > 0.95 * np.sum(ds[0.0].valid)     # (valid: the workbench leaves winches at rest out)
    change = (r1 - r0)[ok]
    # the model is exact on the undelayed recording, and the delay moves every channel
    assert np.abs(r0[ok]).max() < 0.01 * np.abs(change).max()
    assert min(np.sqrt(np.mean(change ** 2, axis=0))) > 0
    assert max(_rel_errors(change, delta * col[ok])) < 0.01
    # minus the model output's time derivative (the column of a plant whose outputs the delay
    # leaves alone) misses the wrench re-formed from the measured tensions: wrong by more than
    # the change itself on the force channels
    y0 = model.with_effects(model.effects, {**model.fixed, "tau": 0.0}).predict(ds[0.0], theta)[0]
    old = -np.gradient(y0, ds[0.0].t, axis=0)[ok]
    assert min(_rel_errors(change[:, :3], delta * old[:, :3])) > 1.0


def test_design_column_is_the_residual_change_of_delayed_feedforward_tensions():
    """The design evaluates the column on the plant's motion dataset (the described platform's
    feedforward tensions) at the linear parameters fitted on that dataset itself: the change of
    the residual when those tensions are the feedforward of the motion at t - delta."""
    desc = default_description()
    t = np.arange(0.0, 20.0, 0.01)
    q, qd, qdd = _sines(t)
    now = motion_dataset(t, q, qd, qdd, desc)
    delta = 0.004
    late = motion_dataset(t, *_sines(t - delta), desc)
    sig = now.signals
    arr = CdprArrays(t=t, tensions=late.signals["tensions"], motor_velocity=now.act_vel,
                     motor_effort=np.full_like(now.act_vel, np.nan), position=q, R=None, acc=qdd,
                     velocity=qd, truth_mass=None, truth_com=None, source="dynamometer",
                     scale=desc.cdpr.gear_ratio / desc.cdpr.drum_radius)
    delayed = dataset_from_arrays(arr, desc, "delayed feedforward")
    np.testing.assert_allclose(delayed.signals["W"], sig["W"])
    base = Model("cdpr", ("cdpr_gravity", "pulley_geometry", "platform_inertia", "time_delay"))
    theta = E.linear_values(base.with_effects(base.effects, {"tau": 0.0}), now)
    assert theta["m"] == pytest.approx(desc.cdpr.platform_mass, rel=1e-6)
    lin = E.Linearised(base, theta)
    col = lin.tau_column(now)
    r0, ok0 = lin.residual(now, 0.0)
    r1, ok1 = lin.residual(delayed, 0.0)
    ok = ok0 & ok1 & np.isfinite(col).all(axis=1)
    change = (r1 - r0)[ok]
    assert np.abs(r0[ok]).max() < 1e-6 * np.abs(now.y).max()
    assert max(_rel_errors(change, delta * col[ok])) < 0.02


def test_excite_cli_designs_for_the_delay_with_cables_taut(tmp_path, capsys):
    ref = tmp_path / "ref"
    assert main(["excite", "--description", default_description_path(), "--params", "tau,m_a",
                 "--duration", "30", "-o", str(ref), "--json"]) == 0
    out = json.loads(capsys.readouterr().out)
    assert out["params"] == ["tau", "m_a"] and out["duration"] == pytest.approx(30.0)
    assert out["condition_before"] is None and 1.0 <= out["condition_after"] < 10.0
    assert "time_delay" in out["model"] and "platform_inertia" in out["model"]
    desc = default_description()
    lim = E.get_exciter("cdpr").limits(desc)
    t = np.arange(int(30.0 * 100) + 1) / 100.0
    q, qd, qdd = E.read_reference(ref, REFERENCE, lim.joints)(t)
    # the lead-in starts outside the box (point A): the box's positions are checked after it
    box = dataclasses.replace(lim, lower=np.minimum(lim.lower, q[0]), upper=np.maximum(lim.upper, q[0]))
    assert box.check(q, qd, qdd) == []
    run = simulate(desc, CdprTruth(payload_mass=122.0, tension_noise=2.0), reference=Trajectory(t, q, qd, qdd),
                   rate=100.0)
    assert not run.slack.any()
    assert run.true_tension.min() > PdffConfig().min_tension
