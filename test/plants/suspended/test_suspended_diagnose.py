"""A9 diagnosis on simulated suspended bags (spec 000_suspended.md sec. 8): a hidden cable
effect in the truth is ranked first and significant with its parameter within 20 %, and a
control bag (nothing hidden) shows nothing significant. Through the workbench: bag -> dataset ->
``diagnose --greedy``."""
import numpy as np
import pytest

from cablelab import workbench
from cablelab.plants.suspended.bag import description_yaml, write_run
from cablelab.plants.suspended.mjcf import build_virtual
from cablelab.plants.suspended.params import parameter_set
from cablelab.plants.suspended.sim import initial_state, simulate


def _bag(tmp_path, name, p, q0, duration, variant="licas"):
    m = build_virtual(p)
    r = simulate(m, initial_state(m, q0), duration)[0]
    path = tmp_path / name
    write_run(path, r, p.S, description_yaml(variant), pos_noise=1e-3, seed=7)
    return path


def _diagnose(path):
    plant, desc, ds = workbench.load(path)
    model = workbench.build_model(plant, desc)
    return workbench.diagnose(ds, model, plant.candidates(desc), greedy_mode=True).to_json()


Y_SWING = {"J8": 0.22, "J11": -0.22}


def test_a9_hidden_coulomb_friction_found_first_within_20_percent(tmp_path):
    p = parameter_set("licas")
    out = _diagnose(_bag(tmp_path, "hidden", p.replace(fs=(0.0, 0.5, 0.5)), Y_SWING, 10.0))
    first = out["ranking"][0]
    assert first["effect"] == "cable_joint_coulomb_friction" and first["significant"]
    assert first["params"]["fs8"] == pytest.approx(0.5, rel=0.2)
    assert out["greedy"][1]["added"] == "cable_joint_coulomb_friction"
    assert out["final"]["error"] < 0.6 * out["baseline"]["error"]     # the error falls


def test_a9_control_bag_nothing_significant(tmp_path):
    p = parameter_set("licas")
    out = _diagnose(_bag(tmp_path, "control", p, Y_SWING, 10.0))
    assert not any(r["significant"] for r in out["ranking"])
    assert len(out["greedy"]) == 1
    # the baseline's viscous friction is the generating f_v8 (000 Table 5: 1.33 N m s/rad)
    assert out["final"]["params"]["fv8"] == pytest.approx(1.33, rel=0.2)


def test_a9_cranebot_yaw_return_ranked_first(tmp_path):
    p = parameter_set("cranebot")                 # truth k_p,10 = 551.3 (repo, D2)
    out = _diagnose(_bag(tmp_path, "yaw", p, {"J7": 0.2}, 15.0, "cranebot"))
    first = out["ranking"][0]
    assert first["effect"] == "virtual_yaw_stiffness" and first["significant"]


def test_cli_diagnose_greedy_json_on_a_suspended_bag(tmp_path, capsys):
    import json

    from cablelab.cli import main as cli

    p = parameter_set("licas")
    bag = _bag(tmp_path, "hidden_cli", p.replace(fs=(0.0, 0.5, 0.5)), Y_SWING, 10.0)
    assert cli(["diagnose", "--greedy", "--json", str(bag)]) == 0
    out = json.loads(capsys.readouterr().out)
    assert out["plant"] == "suspended" and out["ranking"][0]["effect"] == "cable_joint_coulomb_friction"
    assert out["final"]["params"]["fs8"] == pytest.approx(0.5, rel=0.2)


def _elastic_bag(tmp_path, name, elasticity):
    """CRANEbot x swing + yaw, truth with an axial rope spring-damper (or rigid), the rope let go
    30 mm above its static stretch: the platform bounces on the rope."""
    from cablelab.plants.suspended.dataset import radial_mass

    p = parameter_set("cranebot")
    m = build_virtual(p, cable_elasticity=elasticity)
    q0 = {"J9": 0.08, "J7": 0.2}
    if elasticity is not None:
        q0["rope"] = -radial_mass(p) * 9.81 / elasticity[0] + 0.03
    r = simulate(m, initial_state(m, q0), 15.0)[0]
    path = tmp_path / name
    write_run(path, r, p.S, description_yaml("cranebot"), pos_noise=1e-3, seed=7)
    return path


def test_hidden_cable_elasticity_found_first_with_its_stiffness(tmp_path):
    # truth: k_c = 1e4 N/m, c_c = 100 N s/m (bounce at sqrt(k_c / M_r) = 1.15 Hz); the nominal
    # virtual-joint model has a rigid rope
    out = _diagnose(_elastic_bag(tmp_path, "elastic", (1e4, 100.0)))
    first = out["ranking"][0]
    assert first["effect"] == "cable_elasticity" and first["significant"]
    assert first["params"]["k_c"] == pytest.approx(1e4, rel=0.2)
    assert first["params"]["c_c"] == pytest.approx(100.0, rel=0.5)
    assert out["greedy"][1]["added"] == "cable_elasticity"
    assert out["final"]["error"] < 0.6 * out["baseline"]["error"]


def test_rigid_rope_control_does_not_call_elasticity(tmp_path):
    path = _elastic_bag(tmp_path, "rigid", None)
    plant, desc, ds = workbench.load(path)
    assert not ds.signals["excited"][3]              # the cable length stays put (noise only)
    out = _diagnose(path)
    el = next(r for r in out["ranking"] if r["effect"] == "cable_elasticity")
    assert not el["significant"]
    assert "cable_elasticity" not in [g["added"] for g in out["greedy"]]
