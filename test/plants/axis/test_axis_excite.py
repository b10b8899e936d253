"""``cablelab excite`` on the axis: a drive that only ever moves one way confounds its Coulomb
friction Fc with the sensor offset OF (sign(qd) is the constant 1, the offset's column); the
designed reference (Fourier series, the pair's condition number minimised) stays inside the
axis's envelope when the MuJoCo axis tracks it, and a fit on that simulated run separates the
two and finds both.

Oracle: the MuJoCo axis (plants/axis/truth.py, a position servo tracking the reference) with a
known Coulomb friction and offset; the limits are the axis exciter's envelope."""
import json
from pathlib import Path

import numpy as np
import pytest

import cablelab.plants.axis as axis_pkg
from cablelab.bags import BagWriter
from cablelab.cli import main
from cablelab.excite import get_exciter, read_reference
from cablelab.fit import identify
from cablelab.plants.axis.excite import effort_bound
from cablelab.plants.axis.sim import AxisTruth
from cablelab.plants.axis.topics import JOINT_STATES, REFERENCE
from cablelab.plants.axis.truth import simulate_axis
from cablelab.workbench import build_model, load

DESC = (Path(axis_pkg.__file__).parent / "data" / "emps.yaml").read_text()
TRUTH = AxisTruth(inertia=95.0, viscous=200.0, coulomb=20.0, offset=-5.0)
NOISE = 1.0


def _one_way(t):
    """A creep that never reverses: 0.02 m/s with a ripple of +-0.0126 m/s."""
    return -0.2 + 0.02 * t + 0.004 * np.sin(np.pi * t)


def _write(path, run):
    with BagWriter(path) as w:
        w.write_description(DESC)
        w.write_joint_states(JOINT_STATES, run.t, ["joint"], position=run.q[:, None],
                             effort=run.effort[:, None])


@pytest.fixture(scope="module")
def one_way(tmp_path_factory):
    path = tmp_path_factory.mktemp("axis_excite") / "one_way"
    _write(path, simulate_axis(_load_desc(), TRUTH, duration=20.0, reference_fn=_one_way,
                               noise_effort=NOISE))
    return str(path)


def _load_desc():
    from cablelab.description import load_description

    return load_description(DESC)


def test_designed_reference_separates_coulomb_friction_and_offset(one_way, tmp_path, capsys):
    plant, desc, ds = load(one_way)
    model = build_model(plant, desc, ["joint_coulomb_friction", "torque_sensor_offset"])
    r0 = identify(model, ds)
    # confounded: the one-way recording cannot tell them apart (one is held, Fc absorbs both)
    assert r0.params["Fc"] + r0.params["OF"] == pytest.approx(TRUTH.coulomb + TRUTH.offset, abs=1.0)
    assert abs(r0.params["OF"] - TRUTH.offset) > 2.0
    ref = tmp_path / "ref"
    assert main(["excite", one_way, "--params", "Fc,OF", "--duration", "60", "-o", str(ref),
                 "--json"]) == 0
    out = json.loads(capsys.readouterr().out)
    before = np.inf if out["condition_before"] is None else out["condition_before"]   # JSON null: inf
    print(f"axis Fc,OF condition number: before {before:.3g}, after {out['condition_after']:.3g}")
    assert out["params"] == ["Fc", "OF"] and out["duration"] == pytest.approx(60.0)
    assert out["condition_after"] < 5 and out["condition_after"] < before / 10
    # the axis tracks the designed reference: inside the envelope, effort within its bound
    lim = get_exciter("axis").limits(desc)
    play = read_reference(ref, REFERENCE, list(lim.joints))
    q_ref, qd_ref, qdd_ref = play(np.arange(0.0, 60.0, 0.002))
    assert lim.check(q_ref, qd_ref, qdd_ref) == []
    run = simulate_axis(desc, TRUTH, duration=60.0, reference_fn=play, noise_effort=NOISE)
    assert run.q.min() >= lim.lower[0] - 5e-3 and run.q.max() <= lim.upper[0] + 5e-3
    assert np.abs(run.effort_true).max() <= effort_bound(desc, TRUTH.viscous, TRUTH.coulomb)
    # diagnosed on the run: the pair is separated and both come back
    _write(tmp_path / "designed", run)
    _, _, ds2 = load(tmp_path / "designed")
    r = identify(model, ds2)
    assert r.params["Fc"] == pytest.approx(TRUTH.coulomb, rel=0.05)
    assert r.params["OF"] == pytest.approx(TRUTH.offset, abs=0.5)
