"""Proof on hidden cable stretch: the four-cable camera robot (plants/mjcf/examples/cablecam.xml)
simulated forward by MuJoCo (``mj_step``, PD-tracked carriage, winch tensions); the winch
encoders record the rest length each cable has paid out, MuJoCo's tendon length at the true state
less the stretch T / k under MuJoCo's own (noise-free) tension, plus an encoder zero, quantised to
10 um; the tensions carry 0.2 N noise and the joints 18-bit encoders. The analysed model is the
user's rigid-cable model; the oracle is the truth's stiffness per cable. The same motion with
rigid cables (and the same encoder zeros) calls nothing significant."""
import numpy as np
import pytest

from cablelab import workbench
from cablelab.cli import main
from cablelab.diagnose import rank_candidates
from cablelab.plants.mjcf.examples import CABLECAM
from cablelab.plants.mjcf.sim import Hidden, write_bag

CABLES = ["cable_1", "cable_2", "cable_3", "cable_4"]
K = {"cable_1": 30000.0, "cable_2": 25000.0, "cable_3": 35000.0, "cable_4": 28000.0}   # N/m
ZERO = {"cable_1": 0.02, "cable_2": -0.015, "cable_3": 0.0, "cable_4": 0.03}             # m


@pytest.fixture(scope="module")
def bags(tmp_path_factory):
    root = tmp_path_factory.mktemp("tendon")
    xml = CABLECAM.read_text()
    return {name: write_bag(root / name, xml, hidden, duration=20.0, seed=1, tendons=CABLES,
                            cable_lengths=True)
            for name, hidden in (("stretch", Hidden(tendon_stiffness=K, length_offset=ZERO)),
                                 ("rigid", Hidden(length_offset=ZERO)))}


def _diagnose(bag):
    plant, desc, ds = workbench.load(bag)
    return ds, rank_candidates(workbench.build_model(plant, desc), ds, plant.candidates(desc))


def test_length_channels_follow_the_joint_channels(bags):
    plant, desc, ds = workbench.load(bags["rigid"])
    assert ds.channels == ("x", "y", "z") + tuple(f"{c} length" for c in CABLES)
    assert ds.units[3:] == ("m",) * 4
    # rigid cables: the nominal (MuJoCo's ten_length at the measured joints plus the referenced
    # zero) is the encoder reading within quantisation and the conditioning's filter
    from cablelab.model import KNOWN_OUTPUT

    r = (ds.y - ds.signals[KNOWN_OUTPUT])[ds.valid, 3:]
    assert np.sqrt(np.mean(r**2)) < 5e-5
    assert ds.signals["length_zero"] == pytest.approx([ZERO[c] for c in CABLES], abs=2e-5)


def test_hidden_stretch_ranks_first_significant_and_k_recovered(bags):
    _, d = _diagnose(bags["stretch"])
    top = d.ranking[0]
    assert top.effect == "tendon_elasticity", [(r.effect, r.error_after) for r in d.ranking]
    assert top.significant, top
    for c, k in K.items():
        assert top.params[f"k[{c}]"] == pytest.approx(k, rel=0.10), top.params
        assert top.params[f"zero[{c}]"] == pytest.approx(ZERO[c], abs=1e-4), top.params
        assert top.units[f"k[{c}]"] == "N/m" and top.units[f"EA[{c}]"] == "N"
    # the force channels do not see the stretch: no other effect is called
    assert not [r.effect for r in d.ranking[1:] if r.significant]


def test_rigid_cables_call_nothing_significant(bags):
    _, d = _diagnose(bags["rigid"])
    assert not [r.effect for r in d.ranking if r.significant], \
        [(r.effect, r.gain, r.p_value) for r in d.ranking]


def test_without_lengths_the_effect_says_why(tmp_path, capsys):
    bag = write_bag(tmp_path / "nolen", CABLECAM.read_text(), Hidden(), duration=6.0, seed=2,
                    tendons=CABLES)
    assert main(["identify", bag, "--effects", "tendon_elasticity", "--json"]) != 0
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and "no cable lengths" in err[0] and "cable_tensions position" in err[0]
