"""Parameters a free swing cannot determine (the arm coupling without arm motion) are held at
their description or neutral values with a warning naming them, instead of every verb refusing
the model; ``--strict`` keeps the refusal. Data: the MuJoCo virtual-joint platform swinging
freely (plants/suspended/sim.py)."""
import json

import pytest

from cablelab.cli import main
from cablelab.plants.suspended.bag import description_yaml, write_run
from cablelab.plants.suspended.mjcf import build_virtual
from cablelab.plants.suspended.params import parameter_set
from cablelab.plants.suspended.sim import initial_state, simulate

EFFECTS = "platform_levelling,arm_coupling"


@pytest.fixture(scope="module")
def swing(tmp_path_factory):
    p = parameter_set("licas")
    m = build_virtual(p)
    r = simulate(m, initial_state(m, {"J8": 0.22, "J11": -0.22}), 10.0)[0]
    path = tmp_path_factory.mktemp("susp") / "free_swing"
    write_run(path, r, p.S, description_yaml("licas"), pos_noise=1e-3, seed=7)
    return str(path)


@pytest.mark.parametrize("verb", ["compare", "identify", "diagnose"])
def test_free_swing_with_arm_coupling_runs_and_names_what_it_held(swing, verb, capsys):
    extra = ["--folds", "0"] if verb == "identify" else \
        ["--candidates", "pose_sensor_offset", "--folds", "3"] if verb == "diagnose" else []
    assert main([verb, swing, "--effects", EFFECTS, "--json", *extra]) == 0
    out = json.loads(capsys.readouterr().out)
    assert set(out["held"]) == {"arm_x", "arm_y"}
    assert all(v == 0.0 for v in out["held"].values())        # neutral: no coupling
    warn = [w for w in out["warnings"] if "not excited" in w]
    assert len(warn) == 1 and "arm_x" in warn[0] and "arm_y" in warn[0]
    if verb != "diagnose":
        assert out["params"]["arm_x"]["held"] and out["params"]["mgl_x"]["value"] > 0


def test_strict_keeps_the_refusal(swing, capsys):
    assert main(["identify", swing, "--effects", EFFECTS, "--folds", "0", "--strict"]) == 2
    err = capsys.readouterr().err
    assert "rank-deficient" in err and "arm_x" in err


def test_levelling_gains_held_at_the_description_parameter_set(swing):
    """A model whose levelling tilt is never measured off zero: the gains come from the
    description's parameter set (repo LiCAS: kp11 682.4 N m/rad), not from nowhere."""
    import numpy as np

    from cablelab.fit import identify
    from cablelab.workbench import build_model, load

    plant, desc, ds = load(swing)
    ds = ds.replace(signals={**ds.signals, "tilt": np.zeros_like(ds.signals["tilt"]),
                             "tilt_d": np.zeros_like(ds.signals["tilt_d"])})
    r = identify(build_model(plant, desc, ["platform_levelling"]), ds)
    assert r.held == pytest.approx({"kp11": 682.4, "kp12": 712.3, "kd11": 0.01, "kd12": 0.01})
