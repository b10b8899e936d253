"""The crane reference bags through the command line (CONTRACT sec. 5): estimate, diagnose, identify."""
import json
from pathlib import Path

import numpy as np
import pytest

from cablelab.cli import main

BAGS = Path(__file__).resolve().parents[3] / "bags"


def _json(capsys, argv):
    code = main(argv)
    out = capsys.readouterr().out
    assert code == 0, out
    return json.loads(out)


def test_estimate_reports_swing_and_dropouts(capsys, tmp_path):
    out = _json(capsys, ["estimate", str(BAGS / "crane_tilt"), "--json", "--out", str(tmp_path / "est")])
    assert out["plant"] == "crane" and out["samples"] == 1500
    assert out["conditioning"]["dropouts"] > 0 and any("dropouts" in p for p in out["problems"])
    # 1 mm motion-capture noise on a ~0.55 m rope: a few mrad of swing-angle error
    assert out["rms_error_vs_ground_truth"]["theta1"] < 0.005
    assert out["rms_error_vs_ground_truth"]["rope_length"] < 0.003
    from cablelab.bags import open_bag

    est = open_bag(tmp_path / "est").joint_state("/crane/swing_estimate")
    assert est.names == ["theta1", "theta2", "rope_length"] and est.t.size == 1500


def test_estimate_missing_topic_is_one_line_error(capsys, tmp_path):
    from cablelab.bags import BagWriter

    with BagWriter(tmp_path / "b") as w:
        w.write_description((BAGS.parent / "src/cablelab/cablelab/plants/crane/data/crane.yaml").read_text())
        w.write_joint_states("/crane/joint_states", [0.0, 0.1], ["slew", "luff", "hoist"], np.zeros((2, 3)))
    code = main(["estimate", str(tmp_path / "b"), "--json"])
    err = capsys.readouterr().err
    assert code == 2 and "/crane/boom_tip_pose" in err and len(err.strip().splitlines()) == 1


@pytest.mark.parametrize("bag, first", [("crane_tilt", "base_tilt"),
                                        ("crane_no_counterbalance", "counterbalance")])
def test_diagnose_names_the_missing_effect(capsys, bag, first):
    out = _json(capsys, ["diagnose", str(BAGS / bag), "--json"])
    assert out["ranking"][0]["effect"] == first and out["ranking"][0]["significant"]


def test_diagnose_control_bag_nothing_significant(capsys):
    out = _json(capsys, ["diagnose", str(BAGS / "crane_control"), "--json"])
    # the bag's efforts carry no noise, so the one thing the exact model sees is the simulator's
    # zero-order hold: the command recorded with a state acts over the next 1 ms MuJoCo step, an
    # effort leading the motion by half a step (tau = -0.5 ms); nothing physical is significant
    sig = [r for r in out["ranking"] if r["significant"]]
    assert all(r["effect"] == "time_delay" for r in sig), sig
    for r in sig:
        assert -0.7e-3 < r["params"]["tau"] < -0.3e-3, r


def test_identify_with_tilt_gives_the_simulated_parameters(capsys):
    out = _json(capsys, ["identify", str(BAGS / "crane_tilt"), "--effects", "base_tilt",
                         "--fix", "l_c=0.3", "--json"])
    p = {k: v["value"] for k, v in out["params"].items()}
    truth = {"m": 0.5, "m_b": 1.0, "m_c": 2.0, "I_tot": 0.05, "I_b": 0.02}
    for k, v in truth.items():
        assert p[k] == pytest.approx(v, rel=0.25, abs=0.01), (k, p[k])
    assert not out["fit"]["active_bounds"]


def test_free_run_shows_the_missing_counterbalance(capsys):
    """002 sec. 6.4 / Fig. 6.3: the same efforts into the model with and without the
    counterbalance; only the model with it follows the measured motion."""
    bag = str(BAGS / "crane_no_counterbalance")
    without = _json(capsys, ["compare", bag, "--json"])["free_run"]
    with_cb = _json(capsys, ["compare", bag, "--effects", "counterbalance", "--fix", "m_b=1.0",
                             "--json"])["free_run"]
    assert with_cb["nrmse"] < 0.1 and without["nrmse"] > 10 * with_cb["nrmse"]
    assert set(with_cb["channels"]) == {"alpha", "beta", "d", "theta1", "theta2"}


def test_simulation_based_fit_recovers_a_perturbed_boom_mass():
    """Free-run (simulation-based) identification: start m_b 30 % off, the fit of the motion
    brings it back to the simulated 1.0 kg."""
    from cablelab.fit import identify
    from cablelab.model import Model
    from cablelab.plants.crane import plant as C
    from cablelab.plants.crane.freerun import fit_free_run
    from cablelab.workbench import load

    _, desc, ds = load(str(BAGS / "crane_control"))
    start = identify(Model("crane", C.baseline(desc), {"l_c": 0.3}), ds).params
    start = dict(start, m_b=1.3)
    sf = fit_free_run(ds, start, free=("m_b",), max_iter=10)
    assert sf.params["m_b"] == pytest.approx(1.0, abs=0.05)
    assert sf.pearson > 0.99
