"""Proof on hidden effects: bags of the example arm (plants/mjcf/examples/arm3.xml) recorded from
a separate simulator configuration, MuJoCo forward simulation (``mj_step``, explicit Euler) of the
user's model edited with MjSpec to hold the hidden effect (a payload body, joint damping,
armature, a torque-constant error), PD-tracked, with 18-bit encoders and effort noise. The analysed
model is the user's model as given; the oracle is the truth's parameters (Coulomb friction is
MuJoCo's ``frictionloss``, a soft constraint, not the sign function the effect fits)."""
import json

import pytest

from cablelab import workbench
from cablelab.cli import main
from cablelab.diagnose import rank_candidates
from cablelab.plants.mjcf.examples import ARM3, text
from cablelab.plants.mjcf.sim import Hidden, write_bag

ARM_XML = text(ARM3)

CASES = {
    "payload": (Hidden(payload=("tool", 1.5, (0.04, 0.0, 0.0))), "payload_mass", {"m": 1.5}, 0.05),
    "viscous": (Hidden(damping={"base_yaw": 0.8, "shoulder": 1.5, "elbow": 0.6}),
                "joint_viscous_friction",
                {"Fv[base_yaw]": 0.8, "Fv[shoulder]": 1.5, "Fv[elbow]": 0.6}, 0.10),
    "armature": (Hidden(armature={"base_yaw": 0.05, "shoulder": 0.08, "elbow": 0.03}),
                 "joint_armature", {"armature[base_yaw]": 0.05, "armature[shoulder]": 0.08,
                                    "armature[elbow]": 0.03}, 0.10),
    "coulomb": (Hidden(frictionloss={"base_yaw": 0.3, "shoulder": 0.6, "elbow": 0.25}),
                "joint_coulomb_friction", {"Fc[base_yaw]": 0.3, "Fc[shoulder]": 0.6,
                                           "Fc[elbow]": 0.25}, 0.10),
    "gain": (Hidden(gain={"base_yaw": 1.08, "shoulder": 0.9, "elbow": 1.1}), "actuator_gain",
             {"gain[base_yaw]": 1.08, "gain[shoulder]": 0.9, "gain[elbow]": 1.1}, 0.10),
    "spring": (Hidden(stiffness={"shoulder": (6.0, -0.3), "elbow": (3.0, 0.4)}), "joint_spring",
               {"k[shoulder]": 6.0, "k[elbow]": 3.0, "q0[shoulder]": -0.3, "q0[elbow]": 0.4}, 0.10),
}


@pytest.fixture(scope="module")
def bags(tmp_path_factory):
    root = tmp_path_factory.mktemp("mjcf")
    out = {}
    for name, (hidden, *_rest) in {**CASES, "control": (Hidden(),)}.items():
        out[name] = write_bag(root / name, ARM_XML, hidden, duration=12.0, seed=3,
                              payload_body="tool")
    return out


def _diagnose(bag):
    plant, desc, ds = workbench.load(bag)
    model = workbench.build_model(plant, desc)
    return rank_candidates(model, ds, plant.candidates(desc))


@pytest.mark.parametrize("case", sorted(CASES))
def test_hidden_effect_ranks_first_significant_and_recovered(bags, case):
    _, effect, truth, tol = CASES[case]
    d = _diagnose(bags[case])
    top = d.ranking[0]
    assert top.effect == effect, [(r.effect, r.error_after) for r in d.ranking]
    assert top.significant, top
    for name, value in truth.items():
        assert top.params[name] == pytest.approx(value, rel=tol), (name, top.params)


def test_payload_centre_of_mass_is_recovered(bags):
    d = _diagnose(bags["payload"])
    p = d.ranking[0].params
    assert p["com_x"] == pytest.approx(0.04, abs=0.005) and abs(p["com_y"]) < 0.005, p


def test_control_bag_calls_nothing_significant(bags, capsys):
    """Through the command line: the nominal model alone (no effect) is a model to diagnose."""
    assert main(["diagnose", bags["control"], "--json"]) == 0
    out = json.loads(capsys.readouterr().out)
    assert out["plant"] == "mjcf" and out["baseline"]["effects"] == []
    assert not [r["effect"] for r in out["ranking"] if r["significant"]], out["ranking"]
    assert out["baseline"]["error"] < 0.02       # the nominal model explains the record


def test_identify_cli_on_an_mjcf_bag(bags, capsys):
    assert main(["identify", bags["payload"], "--effects", "payload_mass", "--json"]) == 0
    out = json.loads(capsys.readouterr().out)
    assert out["plant"] == "mjcf"
    assert out["params"]["m"]["value"] == pytest.approx(1.5, rel=0.05)


def test_link_inertia_base_parameters_of_a_heavier_forearm(tmp_path, capsys):
    """The forearm 0.6 kg heavier at its centre of mass (0.17 m from the elbow): MuJoCo's columns
    give the base parameters of the classical lumping, dh_x = 0.6 x 0.17 and dI_yy = 0.6 x 0.17^2
    about the elbow; the mass itself moves to the upper arm's first moment and inertia at the
    elbow (0.4 m): dh_x = 0.6 x 0.4, dI_yy = 0.6 x 0.4^2."""
    bag = write_bag(tmp_path / "link", ARM_XML, Hidden(link_mass={"fore": 0.6}), seed=3)
    assert main(["identify", bag, "--effects", "link_inertia", "--json"]) == 0
    out = json.loads(capsys.readouterr().out)
    p = {k: v["value"] for k, v in out["params"].items()}
    assert out["fit"]["cv_nrmse"] < 0.01
    assert p["dhx[fore]"] == pytest.approx(0.6 * 0.17, rel=0.05)
    assert p["dIyy[fore]"] == pytest.approx(0.6 * 0.17**2, rel=0.10)
    assert p["dhx[upper]"] == pytest.approx(0.6 * 0.4, rel=0.05)
    assert p["dIyy[upper]"] == pytest.approx(0.6 * 0.4**2, rel=0.10)


def test_gantry_crane_payload_with_free_swing(tmp_path):
    """The overhead crane example: bridge, trolley and hoist driven, the payload swinging freely
    in two directions (no actuator: those channels are the zero-force equations). A 20 kg load on
    the hook is found first, its mass within 5 %."""
    from cablelab.plants.mjcf.examples import GANTRY

    bag = write_bag(tmp_path / "gantry", GANTRY.read_text(), Hidden(payload=("hook", 20.0, (0, 0, -0.05))),
                    duration=20.0, seed=1, payload_body="hook")
    plant, desc, ds = workbench.load(bag)
    assert ds.channels == ("bridge", "trolley", "swing_y", "swing_x", "hoist")
    assert not ds.y[:, 2:4].any()                 # unactuated: zero-force equations
    d = rank_candidates(workbench.build_model(plant, desc), ds, plant.candidates(desc))
    top = d.ranking[0]
    assert top.effect == "payload_mass" and top.significant, d.ranking[:2]
    assert top.params["m"] == pytest.approx(20.0, rel=0.05)


def test_cable_camera_payload_from_measured_tensions(tmp_path):
    """The four-cable camera robot example: the carriage is not driven at its joints; the four
    winch tensions, measured, enter through MuJoCo's tendon Jacobian (cables wrapping over the
    mast-top pulleys). A 1.5 kg camera on the 6 kg carriage is found first, its mass within 5 %;
    the torque-constant effect has nothing to act on (no joint effort is measured)."""
    from cablelab.plants.mjcf.examples import CABLECAM

    cables = ["cable_1", "cable_2", "cable_3", "cable_4"]
    bag = write_bag(tmp_path / "cam", CABLECAM.read_text(), Hidden(payload=("carriage", 1.5, (0, 0, -0.1))),
                    duration=20.0, seed=1, payload_body="carriage", tendons=cables)
    plant, desc, ds = workbench.load(bag)
    assert ds.channels == ("x", "y", "z") and not ds.signals["driven"].any()
    d = rank_candidates(workbench.build_model(plant, desc), ds, plant.candidates(desc))
    top = d.ranking[0]
    assert top.effect == "payload_mass" and top.significant, d.ranking[:2]
    assert top.params["m"] == pytest.approx(1.5, rel=0.05)
    gain = next(r for r in d.ranking if r.effect == "actuator_gain")
    assert not gain.significant


def test_greedy_finds_two_hidden_effects_in_order(tmp_path):
    """Payload (large) and elbow viscous friction (small) hidden together: the waterfall adds
    payload_mass, then joint_viscous_friction, then stops; both recovered."""
    from cablelab.diagnose import greedy

    hidden = Hidden(payload=("tool", 1.0, (0.03, 0.0, 0.0)), damping={"elbow": 0.4})
    bag = write_bag(tmp_path / "two", ARM_XML, hidden, duration=12.0, seed=7, payload_body="tool")
    plant, desc, ds = workbench.load(bag)
    steps = greedy(workbench.build_model(plant, desc), ds, plant.candidates(desc), max_steps=3)
    assert [s.added for s in steps[1:]] == ["payload_mass", "joint_viscous_friction"], \
        [(s.added, s.error) for s in steps]
    final = steps[2].params
    assert final["m"] == pytest.approx(1.0, rel=0.05)
    assert final["Fv[elbow]"] == pytest.approx(0.4, rel=0.10)
