"""Workbench verbs end to end on small synthetic bags: report contents, bad input as one-line
errors (exit 2, no traceback), CSV import."""
import json

import numpy as np
import pytest

from cablelab.bags import BagWriter
from cablelab.cli import main
from cablelab.description import load_description
from cablelab.plants.axis.sim import AxisTruth
from cablelab.plants.axis.truth import simulate_axis

DESC = "plant: axis\nname: synthetic slide\naxis:\n  joint_type: prismatic\n  inertia: 2.0\n"


def _write(path, t, q, effort, desc=DESC, topic="/axis/joint_states"):
    with BagWriter(path) as w:
        if desc:
            w.write_description(desc)
        w.write_joint_states(topic, t, ["joint"], q[:, None], None, effort[:, None])
    return str(path)


@pytest.fixture(scope="module")
def synth_bag(tmp_path_factory):
    run = simulate_axis(load_description(DESC), AxisTruth(inertia=2.0, viscous=5.0, coulomb=1.0),
                        duration=12.0, fs=250.0, amplitude=0.3, noise_effort=0.05, seed=1)
    return _write(tmp_path_factory.mktemp("bags") / "axis", run.t, run.q, run.effort)


def _err(capsys, argv) -> str:
    assert main(argv) == 2
    err = capsys.readouterr().err.strip()
    assert err.count("\n") == 0 and "Traceback" not in err, err
    return err


def test_report_writes_html_with_all_figures(synth_bag, tmp_path, capsys):
    out = tmp_path / "rep"
    assert main(["report", synth_bag, "-o", str(out), "--json"]) == 0
    res = json.loads(capsys.readouterr().out)
    html = (out / "index.html").read_text()
    for fig in res["figures"]:
        assert (out / fig).stat().st_size > 1000
        assert f"src='{fig}'" in html
    for name in ("waterfall.png", "overlay.png", "residual_time.png", "regimes_0.png", "whiteness_0.png"):
        assert name in res["figures"]
    assert res["final"][-1] == "joint_coulomb_friction"
    assert "joint_coulomb_friction" in html and "std. error" in html


def test_report_text_output_states_the_answer(synth_bag, tmp_path, capsys):
    """Without --json the terminal says what is missing (the slide's hidden Coulomb friction) and
    where the page is; the page's answer sentence names the same effect."""
    out = tmp_path / "rep"
    assert main(["report", synth_bag, "-o", str(out)]) == 0
    lines = capsys.readouterr().out.splitlines()
    assert lines[0].startswith("missing: joint_coulomb_friction (held-out NRMSE "), lines
    before, after = (float(x) for x in lines[0].split("NRMSE ")[1].rstrip("%)").split("% ->"))
    assert after < before
    assert lines[-1].startswith("wrote ") and str(out / "index.html") in lines[-1]
    html = (out / "index.html").read_text()
    assert "misses <b>joint_coulomb_friction</b>" in html


def test_bag_without_the_plant_topic(tmp_path, capsys):
    bag = _write(tmp_path / "b", np.arange(100) * 0.01, np.zeros(100), np.zeros(100),
                 topic="/other/joint_states")
    err = _err(capsys, ["diagnose", bag, "--json"])
    assert "/axis/joint_states" in err and "not in the bag" in err


def test_bag_without_description(tmp_path, capsys):
    bag = _write(tmp_path / "b", np.arange(100) * 0.01, np.zeros(100), np.zeros(100), desc=None)
    assert "--description" in _err(capsys, ["compare", bag])


@pytest.mark.parametrize("effect,msg", [("bogus", "unknown effect 'bogus'"),
                                        ("pulley_geometry", "does not apply to plant axis")])
def test_unknown_and_inapplicable_effects(synth_bag, capsys, effect, msg):
    err = _err(capsys, ["diagnose", synth_bag, "--effects", effect, "--json"])
    assert msg in err and "joint_coulomb_friction" in err  # lists the valid ids


def test_too_few_samples_for_the_folds(tmp_path, capsys):
    t = np.arange(300) * 0.01
    bag = _write(tmp_path / "b", t, np.sin(t), np.cos(t))
    err = _err(capsys, ["diagnose", bag, "--folds", "5"])
    assert "samples for 5 folds" in err and "fewer --folds" in err


def test_rank_deficient_fit_names_the_parameter(tmp_path, capsys):
    t = np.arange(2000) * 0.01
    bag = _write(tmp_path / "b", t, 0.1 * t, 3.0 + 0 * t)  # constant velocity: M not excited
    err = _err(capsys, ["identify", bag])
    assert "rank-deficient" in err and "M" in err and "--fix" in err
    # fixing the unexcited parameter makes the fit well-posed
    assert main(["identify", bag, "--fix", "M=2", "--json"]) == 0
    out = json.loads(capsys.readouterr().out)
    assert out["params"]["Fv"]["value"] == pytest.approx(30.0, rel=1e-6)


def test_csv_import_with_scale_factor(tmp_path, capsys):
    path = tmp_path / "d.csv"
    t = np.arange(0, 5, 0.01)
    np.savetxt(path, np.column_stack([t, np.sin(t), np.cos(t)]), delimiter=",", header="time,pos,volt",
               comments="")
    out = tmp_path / "bag"
    assert main(["import", str(path), "--plant", "axis", "--map", "time=time,position=pos,effort=2.5*volt",
                 "--description", DESC, "-o", str(out)]) == 0
    capsys.readouterr()
    from cablelab.bags import open_bag

    js = open_bag(out).joint_state("/axis/joint_states")
    assert np.allclose(js.effort[:, 0], 2.5 * np.cos(t)) and np.allclose(js.position[:, 0], np.sin(t))
    err = _err(capsys, ["import", str(path), "--plant", "axis", "--map", "time=time,effort=2*nope",
                        "--description", DESC, "-o", str(tmp_path / "x")])
    assert "no column 'nope'" in err and "volt" in err


def test_irregular_stamps_and_dropouts_are_conditioned(tmp_path, capsys):
    """Jittered sample times and NaN dropouts (empty fields) are resampled onto a uniform grid;
    the diagnosis still finds the hidden Coulomb friction."""
    run = simulate_axis(load_description(DESC), AxisTruth(inertia=2.0, viscous=5.0, coulomb=1.0),
                        duration=12.0, fs=500.0, amplitude=0.3, noise_effort=0.05, seed=4)
    rng = np.random.default_rng(4)
    keep = np.sort(rng.choice(run.t.size, size=int(0.8 * run.t.size), replace=False))  # 20 % lost
    t = run.t[keep] + rng.uniform(-2e-4, 2e-4, keep.size)  # +-0.2 ms stamp jitter
    q, eff = run.q[keep].copy(), run.effort[keep].copy()
    eff[rng.choice(keep.size, 50, replace=False)] = np.nan  # messages with an empty effort
    bag = _write(tmp_path / "b", t, q, eff)
    assert main(["diagnose", bag, "--json"]) == 0
    out = json.loads(capsys.readouterr().out)
    top = out["ranking"][0]
    assert top["effect"] == "joint_coulomb_friction" and top["significant"]
    assert top["params"]["Fc"] == pytest.approx(1.0, rel=0.1)


def test_identify_with_simulation_based_refinement(synth_bag, capsys):
    assert main(["identify", synth_bag, "--effects", "joint_coulomb_friction", "--simulation", "pearson",
                 "--folds", "0", "--json"]) == 0
    out = json.loads(capsys.readouterr().out)
    sim = out["simulation"]
    assert sim["objective"] == "pearson" and sim["pearson"] > 0.999
    for k, v in {"M": 2.0, "Fv": 5.0, "Fc": 1.0}.items():
        assert sim["params"][k]["value"] == pytest.approx(v, rel=0.06)
        assert out["params"][k]["value"] == pytest.approx(v, rel=0.06)
    assert out["fit"]["cv_nrmse"] is None
