"""The typed plant interface (:mod:`cablelab.plant_interface`): every plant satisfies it, a plant
that does not is refused when it registers, the options a dataset is built with are typed, and a
plant's own command-line options come from its package.

Oracles: the interface's member lists against each registered plant; the effect registry for the
ids a plant's nominal model and candidates name; each plant's example description parsed, dumped
and parsed again to the same section; argparse's own parse of the plant's declared choices."""
from __future__ import annotations

import dataclasses
import os
import subprocess
import sys
from pathlib import Path
from types import SimpleNamespace

import pytest

from cablelab.description import dump_description, load_description
from cablelab.effects import effects_for
from cablelab.errors import CablelabError
from cablelab.plant_interface import (OPTIONAL_HOOKS, REQUIRED_ATTRIBUTES, REQUIRED_METHODS,
                                      DatasetOptions, PlantInterface, cli_options, missing_members)
from cablelab.registry import available_plants, get_plant, register_plant
from robust_helpers import toy_plant_dir

PLANTS = ("axis", "cdpr", "crane", "leg", "suspended")


def test_the_five_plants_are_found():
    assert set(PLANTS) <= set(available_plants())


@pytest.mark.parametrize("name", PLANTS)
def test_every_plant_satisfies_the_interface(name):
    plant = get_plant(name)
    assert isinstance(plant, PlantInterface)
    assert missing_members(plant) == []
    assert plant.name == name and plant.package == f"cablelab.plants.{name}"
    for hook in OPTIONAL_HOOKS:
        assert getattr(plant, hook) is None or callable(getattr(plant, hook))
    # the topics the workbench requires are topics of the contract, with the same type
    for topic, msgtype in plant.topics:
        assert plant.contract_topics[topic] == msgtype


@pytest.mark.parametrize("name", PLANTS)
def test_nominal_model_and_candidates_name_registered_effects_of_the_plant(name):
    plant = get_plant(name)
    data = Path(plant.dataset.__code__.co_filename).parent / "data"
    descs = [load_description(p) for p in sorted(data.glob("*.yaml"))] or [None]
    known = set(effects_for(name))
    for desc in descs:
        base, cands = plant.baseline(desc), plant.candidates(desc)
        assert isinstance(base, tuple) and isinstance(cands, tuple) and base
        assert set(base) <= known, set(base) - known
        assert set(cands) <= known, set(cands) - known


@pytest.mark.parametrize("name", PLANTS)
def test_example_description_round_trips_through_parse_and_dump(name):
    """data/*.yaml of the plant: parse_section -> dump (dump_section or the fields) -> parse gives
    the same section."""
    plant = get_plant(name)
    files = sorted((Path(plant.dataset.__code__.co_filename).parent / "data").glob("*.yaml"))
    assert files, f"plants/{name}/data/ has no example description"
    for f in files:
        desc = load_description(f)
        if desc.plant != name:
            continue
        text = dump_description(desc)
        again = load_description(text)
        assert again.plant == name and dump_description(again) == text


def test_toy_plant_outside_cablelab_satisfies_the_interface():
    code = ("import pendulum_plant; from cablelab.registry import get_plant; "
            "from cablelab.plant_interface import PlantInterface, missing_members; "
            "p = get_plant('pendulum'); print(isinstance(p, PlantInterface), missing_members(p))")
    env = {**os.environ, "PYTHONPATH": os.pathsep.join(filter(None, [str(toy_plant_dir()), os.environ.get("PYTHONPATH")]))}
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, env=env,
                         timeout=300)
    assert out.returncode == 0, out.stderr
    assert out.stdout.split() == ["True", "[]"]


@pytest.mark.parametrize("member", REQUIRED_METHODS)
def test_a_plant_without_a_required_method_is_refused_naming_it(member):
    broken = dataclasses.replace(get_plant("axis"), name="broken_plant", **{member: None})
    with pytest.raises(CablelabError) as err:
        register_plant(broken)
    msg = str(err.value)
    assert "\n" not in msg and "broken_plant" in msg and f"method {member}" in msg
    assert "broken_plant" not in available_plants()


def test_an_object_missing_members_is_refused_naming_each():
    axis = get_plant("axis")
    keep = {k: getattr(axis, k) for k in REQUIRED_ATTRIBUTES + REQUIRED_METHODS + OPTIONAL_HOOKS}
    keep["name"] = "half_plant"
    assert missing_members(SimpleNamespace(**keep)) == []      # the oracle: all members, accepted
    del keep["candidates"], keep["checked_topics"], keep["markers"]
    with pytest.raises(CablelabError) as err:
        register_plant(SimpleNamespace(**keep))
    msg = str(err.value)
    assert "\n" not in msg
    for what in ("method candidates", "attribute checked_topics", "hook markers"):
        assert what in msg
    assert "half_plant" not in available_plants()


def test_options_type_must_be_a_dataclass():
    broken = dataclasses.replace(get_plant("axis"), name="bad_options", options_type=dict)
    with pytest.raises(CablelabError, match="options_type"):
        register_plant(broken)


def test_dataset_options_are_typed_and_refuse_another_plants_option():
    from cablelab.conditioning import Conditioning
    from cablelab.plants.cdpr.options import CdprOptions

    cdpr, axis = get_plant("cdpr"), get_plant("axis")
    opts = DatasetOptions.build(cdpr, {"tensions": "motor", "conditioning": Conditioning(decimate=2)})
    assert opts.plant == CdprOptions(tensions="motor", pose="desired")
    assert opts.conditioning.decimate == 2 and dict(opts.derived_velocity) == {}
    assert DatasetOptions.build(cdpr, {"tensions": None}).plant == CdprOptions()   # None: not given
    assert DatasetOptions.build(axis, None).plant is None
    assert DatasetOptions.build(axis, opts) is opts
    with pytest.raises(CablelabError, match=r"tensions: not an option of plant axis"):
        DatasetOptions.build(axis, {"tensions": "motor"})
    assert opts.plant_options(CdprOptions).tensions == "motor"
    assert DatasetOptions().plant_options(CdprOptions) == CdprOptions()


def test_cdpr_command_line_options_come_from_its_package():
    """--tensions and --pose are the CDPR's options dataclass fields; the verbs offer them because
    the CDPR declares them, with the choices it declares."""
    import argparse

    from cablelab.commands._workbench_args import add_plant_options, plant_cli_options
    from cablelab.plants.cdpr.options import POSE_SOURCES, TENSION_SOURCES

    declared = dict(cli_options(get_plant("cdpr").options_type))
    assert declared["tensions"].flag == "--tensions" and declared["tensions"].choices == TENSION_SOURCES
    assert declared["pose"].flag == "--pose" and declared["pose"].verbs == ("estimate",)
    from cablelab.plants.crane.options import CRANE_FILTERS

    crane = dict(cli_options(get_plant("crane").options_type))
    assert set(crane) == {"crane_filter"} and crane["crane_filter"].choices == CRANE_FILTERS
    for name in PLANTS:
        if name not in ("cdpr", "crane"):
            assert cli_options(get_plant(name).options_type) == []
    assert set(plant_cli_options("compare")) == {"--tensions", "--crane-filter"}
    assert set(plant_cli_options("estimate")) == {"--tensions", "--pose"}
    assert plant_cli_options("estimate")["--pose"][2] == ["cdpr"]
    p = argparse.ArgumentParser()
    add_plant_options(p, "estimate")
    assert p.parse_args(["--pose", "measured"]).pose == "measured"
    assert p.parse_args([]).tensions is None                    # not given: the plant's default
    with pytest.raises(SystemExit):
        p.parse_args(["--tensions", "strain_gauge"])
