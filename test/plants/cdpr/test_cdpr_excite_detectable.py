"""The CDPR's delay design: what it optimises is each motion's own, and the smallest delay it
says the designed run shows is what a recording of that run shows.

Oracles: (1) the single-motion condition number (:func:`cablelab.excite.condition`, QR and Schur
complement of one motion's own dataset) for every block of the stacked evaluation the design's
optimiser differentiates; (2) bench/cases_cdpr_delay.py (its own structure matrix, tension
distribution and sensor noise, none of the fitting code) records the designed reference with
the dynamometers half and twice excite's detectable delay late: the fit with the delay loses
less than the diagnosis' MIN_GAIN of the held-out-free RMS error at half, more at twice."""
import os
import sys

import numpy as np
import pytest

from cablelab import excite as E
from cablelab import workbench
from cablelab.diagnose.ranking import MIN_GAIN
from cablelab.fit import identify
from cablelab.model import Model
from cablelab.plants.cdpr.sim import default_description

sys.path.insert(0, os.path.join(os.path.dirname(__file__), "..", "..", "..", "bench"))
import cases_cdpr_delay  # noqa: E402


def test_stacked_delay_blocks_are_each_motions_own():
    desc = default_description()
    ex = E.get_exciter("cdpr")
    ex = E.replace(ex, **ex.tune(("tau",)))
    lim, h, dur = ex.limits(desc), ex.harmonics, 40.0
    shape = (len(lim.joints), 2, h)
    t = np.arange(0.0, dur, 1.0 / (ex.grid * ex.base_hz * h))
    basis = E.fourier_basis(t, ex.base_hz, h, dur)
    xs = np.random.default_rng(1).normal(size=(3, int(np.prod(shape))))
    base = Model("cdpr", ("cdpr_gravity", "platform_inertia", "time_delay"))
    one = [ex.motion_dataset(t, *E.scaled_motion(x.reshape(shape), t, lim, ex.base_hz, dur), desc) for x in xs]
    lin = E.Linearised(base, E.linear_values(base.with_effects(base.effects, {"tau": 0.0}), one[0]))
    params = ("tau", "m_a")
    single = [E.condition(lin, ds, params) for ds in one]
    stacked = E.stacked_dataset(ex, xs, basis, t, lim, shape, desc, edges=True)
    assert E.block_conditions(lin, stacked, len(xs), params) == pytest.approx(single, rel=1e-9)
    # kept, the rows whose delayed samples reach into the next block make the blocks differ
    raw = E.stacked_dataset(ex, xs, basis, t, lim, shape, desc, edges=False)
    assert E.block_conditions(lin, raw, len(xs), params)[0] != pytest.approx(single[0], rel=1e-6)


def _gain(model, ds):
    """The RMS error the fit with the delay free removes (geometric mean over the wrench channels)
    against the fit without it."""
    rms = []
    for m in (model.with_effects(model.effects, {**model.fixed, "tau": 0.0}), model):
        r = identify(m, ds, on_deficient="hold").residual
        r = r[np.isfinite(r).all(axis=1)]
        rms.append(np.sqrt(np.mean(r ** 2, axis=0)))
    return float(1.0 - np.exp(np.mean(np.log(rms[1] / rms[0]))))


def test_detectable_delay_is_what_the_designed_run_shows(tmp_path):
    case = cases_cdpr_delay.draw_delay_case(9009)
    tr = case.truth
    tr["duration"] = tr["first_s"]
    cases_cdpr_delay.write_bag(case, tmp_path / "first")
    plant, desc, ds0 = workbench.load(tmp_path / "first", None, dict(case.options))
    d = E.design("cdpr", desc, tr["pair"], duration=tr["designed_s"], before_ds=ds0, seed=case.seed,
                 effects=case.effects, fixed=case.fixed, max_iter=10)
    det = d.detectable
    assert det is not None and 0 < det["by_test"] < det["by_gain"] == det["tau"] < 0.05
    assert "detectable" in d.to_json()
    model = workbench.build_model(plant, desc, tuple(case.effects) + ("time_delay",), fixed=case.fixed)
    tr["duration"], tr["reference"] = tr["designed_s"], cases_cdpr_delay.tabulated(d.t, d.q, d.qd, d.qdd)
    gains = {}
    for factor in (0.5, 2.0):
        tr["tau"] = factor * det["tau"]
        cases_cdpr_delay.write_bag(case, tmp_path / f"x{factor}")
        gains[factor] = _gain(model, workbench.load(tmp_path / f"x{factor}", None, dict(case.options))[2])
    print(f"detectable {1e3 * det['tau']:.2f} ms; RMS gain at half {100 * gains[0.5]:.2f} %, twice "
          f"{100 * gains[2.0]:.2f} %")
    assert gains[0.5] < MIN_GAIN < gains[2.0]


def test_excite_cli_reports_the_smallest_delay(tmp_path, capsys):
    from cablelab.cli import main

    case = cases_cdpr_delay.draw_delay_case(9011)              # a control: nothing late
    case.truth["duration"] = 30.0
    cases_cdpr_delay.write_bag(case, tmp_path / "first")
    args = ["excite", str(tmp_path / "first"), "--tensions", "dynamometer", "--params", "tau,m_a",
            "--duration", "30", "-o"]
    assert main(args + [str(tmp_path / "ref")]) == 0
    text = capsys.readouterr().out
    assert "smallest delay this run shows:" in text and "first's fit" in text
    assert main(args + [str(tmp_path / "ref2"), "--json"]) == 0
    import json

    det = json.loads(capsys.readouterr().out)["detectable"]
    assert det["tau"] == max(det["by_gain"], det["by_test"]) and 0 < det["tau"] < 0.1
    assert f"{1e3 * det['tau']:.3g} ms" in text
