"""``cablelab excite`` on the crane: a recording that holds the luff still confounds the
counterbalance mass m_c with the luff torque offset OF[luff] (the counterbalance's gravity
torque m_c l_c g cos(beta) is a constant at one luff angle); the designed reference (Fourier
series per joint, the condition number of the pair's information minimised) stays inside the
crane's limits when the MuJoCo crane tracks it, and a fit on that simulated run separates the
two and finds both.

Oracle: the MuJoCo crane (plants/crane/sim.py) with a known payload mass and hoist offset;
the limits are the crane exciter's envelope."""
import json

import numpy as np
import pytest

from cablelab.cli import main
from cablelab.diagnose.identifiability import correlations
from cablelab.excite import get_exciter, read_reference
from cablelab.fit import identify
from cablelab.plants.crane.topics import REFERENCE
from cablelab.plants.crane.reference import slew_only
from cablelab.plants.crane.sim import CraneTruth, simulate, write_bag
from cablelab.workbench import build_model, load

from pathlib import Path
import cablelab.plants.crane as crane_pkg

DESC = (Path(crane_pkg.__file__).parent / "data" / "crane.yaml").read_text()
TRUTH = CraneTruth(torque_offset=(0.0, 0.5, 0.0), effort_noise=(0.05, 0.05, 0.1), mocap_noise=0.0005)


def _corr(r, a, b):
    names, corr = correlations(r)
    return corr[names.index(a), names.index(b)]


@pytest.fixture(scope="module")
def confounded(tmp_path_factory):
    path = tmp_path_factory.mktemp("crane_excite") / "slew_only"
    write_bag(path, simulate(TRUTH, 30.0, reference=slew_only()), DESC)
    return str(path)


def test_designed_reference_separates_counterbalance_and_luff_offset(confounded, tmp_path, capsys):
    plant, desc, ds = load(confounded)
    # l_c known (the description's 0.3 m; with it free only m_c l_c and m_c l_c^2 are seen)
    model = build_model(plant, desc, ["torque_sensor_offset"], fixed={"l_c": 0.3}, strict=True)
    assert abs(_corr(identify(model, ds), "m_c", "OF[luff]")) > 0.98        # confounded
    ref = tmp_path / "ref"
    assert main(["excite", confounded, "--params", "OF[luff],m_c", "--duration", "60",
                 "-o", str(ref), "--json"]) == 0
    out = json.loads(capsys.readouterr().out)
    assert set(out) >= {"params", "condition_before", "condition_after", "duration"}
    assert out["params"] == ["OF[luff]", "m_c"] and out["duration"] == pytest.approx(60.0)
    assert out["condition_after"] < out["condition_before"] / 100
    # the crane tracks the designed reference: every joint stays inside the limits
    ex = get_exciter("crane")
    lim = ex.limits(desc)
    play = read_reference(ref, REFERENCE, list(lim.joints))
    q_ref, qd_ref, qdd_ref = play(np.arange(0.0, 60.0, 0.01))
    assert lim.check(q_ref, qd_ref, qdd_ref) == []
    run = simulate(TRUTH, 60.0, reference=play)
    assert np.all(run.q[:, :3] >= lim.lower - 1e-3) and np.all(run.q[:, :3] <= lim.upper + 1e-3)
    assert np.all(np.abs(run.effort) <= np.asarray(TRUTH.effort_limit) + 1.0)   # no saturation
    # diagnosed on the run: the pair is separated and both come back
    write_bag(tmp_path / "designed", run, DESC)
    plant, desc, ds2 = load(tmp_path / "designed")
    r = identify(model, ds2)
    assert abs(_corr(r, "m_c", "OF[luff]")) < 0.9
    assert r.params["m_c"] == pytest.approx(TRUTH.params.counterbalance_mass, rel=0.05)
    assert r.params["OF[luff]"] == pytest.approx(0.5, abs=0.05)


def test_excite_needs_a_known_parameter(confounded, tmp_path, capsys):
    assert main(["excite", confounded, "--params", "nope", "-o", str(tmp_path / "r")]) == 2
    err = capsys.readouterr().err
    assert "nope" in err and "OF[luff]" in err


def test_diagnose_prints_the_excite_command_for_a_confounded_pair(confounded, capsys):
    assert main(["diagnose", confounded, "--candidates", "torque_sensor_offset", "--folds", "3",
                 "--fix", "l_c=0.3"]) == 0
    text = capsys.readouterr().out
    line = next(x for x in text.splitlines() if x.startswith("to separate") and "m_c" in x)
    assert f"cablelab excite {confounded} --params 'OF[luff],m_c' --duration 60 -o " in line
    assert main(["diagnose", confounded, "--candidates", "torque_sensor_offset", "--folds", "3",
                 "--fix", "l_c=0.3", "--json"]) == 0
    out = json.loads(capsys.readouterr().out)
    assert any("'OF[luff],m_c'" in c for c in out["excite"])
