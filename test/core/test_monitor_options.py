"""``model_monitor --plant P`` takes the plant's own options from the plant, not from a list in
the monitor: the fields of the plant's options dataclass that ``cablelab compare`` offers become
ROS parameters of the same name, default and choices (CDPR: ``tensions``; crane:
``crane_filter``), each value reaching the monitor's dataset; other plants have none, and ``--help`` lists what the chosen plant has.

Oracle: the plant's own dataset options (:meth:`DatasetOptions.build`, the path every verb takes)
accept every value the monitor offers, and the monitor built in-process with ``-p`` overrides
hands the chosen value to its :class:`~cablelab.monitor.ResidualMonitor`."""
from __future__ import annotations

from pathlib import Path

import pytest

from test_node_parameters import ros_with  # noqa: F401  (fixture: rclpy with -p overrides)

REPO = Path(__file__).resolve().parents[2]


def test_every_offered_value_is_an_option_of_the_plant_dataset():
    from cablelab.plant_interface import DatasetOptions
    from cablelab.registry import available_plants, get_plant
    from cablelab.ros.monitor_node import PARAMETERS, parameters_for, plant_parameters

    offered = {p: plant_parameters(get_plant(p)) for p in available_plants()}
    assert [s.name for s in offered["cdpr"]] == ["tensions"]         # not pose: estimate only
    tensions = offered["cdpr"][0]
    assert tensions.default == "dynamometer" and {"dynamometer", "motor"} <= set(tensions.choices)
    for plant, specs in offered.items():
        assert parameters_for(plant)[:len(PARAMETERS)] == PARAMETERS
        for spec in specs:
            for value in spec.choices:
                opts = DatasetOptions.build(get_plant(plant), {spec.name: value})
                assert getattr(opts.plant, spec.name) == value
    crane = offered["crane"]                    # the crane's equations' filter, a dataset option
    assert [s.name for s in crane] == ["crane_filter"] and crane[0].default == "positions"
    for plant in ("axis", "leg", "suspended"):
        assert offered[plant] == () and "tensions" not in {s.name for s in parameters_for(plant)}


@pytest.mark.parametrize("choice", ["motor", "both"])
def test_the_chosen_tension_source_reaches_the_monitor_dataset(ros_with, choice):  # noqa: F811
    from cablelab.bags import open_bag
    from cablelab.ros.monitor_node import make_node

    ros_with(f"tensions:={choice}")
    node = make_node("cdpr")
    try:
        assert node.get_parameter("tensions").value == choice
        assert node.describe_parameter("tensions").read_only
        node.set_description(open_bag(REPO / "bags" / "cdpr_m1_reference").description)
        assert node.monitor.options.plant.tensions == choice
    finally:
        node.destroy_node()


def test_bad_or_foreign_option_is_refused(ros_with):  # noqa: F811
    from cablelab.errors import CablelabError
    from cablelab.ros.monitor_node import make_node

    ros_with("tensions:=winch")
    with pytest.raises(CablelabError, match=r"parameter tensions:=winch: expected one of: dynamometer, motor"):
        make_node("cdpr").destroy_node()


def test_axis_monitor_has_no_tension_parameter(ros_with):  # noqa: F811
    from cablelab.ros.monitor_node import make_node

    ros_with("tensions:=motor")
    node = make_node("axis")
    try:
        assert not node.has_parameter("tensions") and node.unknown_parameters() == ["tensions"]
        assert node.options == {}
    finally:
        node.destroy_node()


def test_help_lists_the_plant_options(capsys):
    from cablelab.ros.monitor_node import main

    for plant, has in (("cdpr", True), ("axis", False)):
        with pytest.raises(SystemExit) as exc:
            main(["--plant", plant, "--help"])
        out = capsys.readouterr().out
        assert exc.value.code == 0 and "  band_sigma (double" in out
        assert ("  tensions (string, default 'dynamometer'; one of: dynamometer, motor" in out) is has
