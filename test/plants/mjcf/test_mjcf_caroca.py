"""CAROCA written as MJCF (``plants/mjcf/examples/caroca.xml``, from the cdpr plant's
description): on the CDPR reference bags, the ``mjcf`` plant's payload mass (measured tensions
through MuJoCo's tendon Jacobian, the platform's six joints from the measured pose) agrees with
the ``cdpr`` plant's estimate (the paper's force balance over the swivel-pulley model)."""
import json

import pytest

from cablelab.bags import open_bag
from cablelab.cli import main
from cablelab.plants.mjcf.examples import text
from cablelab.plants.mjcf.examples.caroca import CAROCA, caroca_xml, mjcf_bag

BAGS = ("bags/cdpr_m1_reference", "bags/cdpr_m2_fast")


def test_shipped_file_is_what_the_generator_writes():
    assert text(CAROCA) == caroca_xml()


@pytest.mark.parametrize("bag", BAGS)
def test_payload_mass_agrees_with_the_cdpr_plant(bag, tmp_path, capsys):
    assert main(["estimate", bag, "--json"]) == 0
    cdpr = json.loads(capsys.readouterr().out)["mass"]["mean"]
    assert main(["identify", mjcf_bag(bag, tmp_path / "mjcf"), "--effects", "payload_mass",
                 "--json"]) == 0
    out = json.loads(capsys.readouterr().out)
    platform = open_bag(bag).description.cdpr.platform_mass      # the model's own platform mass
    total = platform + out["params"]["m"]["value"]
    assert total == pytest.approx(cdpr, rel=0.01), (total, cdpr)
