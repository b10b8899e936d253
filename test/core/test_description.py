"""Plant description loader: valid files load, every kind of mistake names its key path."""
from __future__ import annotations

import textwrap

import numpy as np
import pytest

from cablelab.description import dump_description, load_description
from cablelab.errors import CablelabError

CDPR = textwrap.dedent("""\
    plant: cdpr
    name: two-cable test rig
    gravity: 9.81
    cdpr:
      platform_mass: 366.0
      drum_radius: 0.06
      gear_ratio: 40.0
      pulley_radius: 0.15
      cables:
        - exit_point: [-3.5, -2.0, 3.0]
          anchor_point: [-0.5, -0.3, 0.4]
        - exit_point: [3.5, 2.0, 3.0]
          anchor_point: [0.5, 0.3, 0.4]
          swivel_axis: [0, 0, 2]
    """)


def _err(text: str) -> str:
    with pytest.raises(CablelabError) as exc:
        load_description(text)
    msg = str(exc.value)
    assert "\n" not in msg
    return msg


def test_valid_cdpr_loads_with_units_and_normalised_axis():
    d = load_description(CDPR)
    assert d.plant == "cdpr" and d.cdpr.gear_ratio == 40.0 and d.cdpr.pulley_radius == 0.15
    np.testing.assert_array_equal(d.cdpr.exit_points[1], [3.5, 2.0, 3.0])
    np.testing.assert_allclose(d.cdpr.swivel_axes[1], [0, 0, 1])  # normalised
    np.testing.assert_allclose(d.cdpr.swivel_axes[0], [0, 0, 1])  # default +z
    again = load_description(dump_description(d))  # round trip through YAML
    np.testing.assert_array_equal(again.cdpr.anchor_points, d.cdpr.anchor_points)


def test_valid_crane_and_axis():
    c = load_description("plant: crane\ncrane:\n  boom_length: 1.0\n  counterbalance: {mass: 2.0, distance: 0.3}\n")
    assert c.crane.counterbalance.mass == 2.0 and c.gravity == 9.81
    a = load_description("plant: axis\naxis:\n  joint_type: revolute\n  gravity_moment: 0.4\n")
    assert a.axis.joint_type == "revolute" and a.axis.gravity_moment == 0.4


@pytest.mark.parametrize("text, key, what", [
    (CDPR.replace("  gear_ratio: 40.0\n", "  gear_ratio: 40.0\n  gear_ration: 4\n"), "cdpr.gear_ration", "unknown key"),
    (CDPR.replace("  drum_radius: 0.06\n", ""), "cdpr.drum_radius", "missing"),
    (CDPR.replace("drum_radius: 0.06", "drum_radius: big"), "cdpr.drum_radius", "expected a number"),
    (CDPR.replace("anchor_point: [0.5, 0.3, 0.4]", "anchor_point: [0.5, 0.3]"),
     "cdpr.cables[1].anchor_point", "expected 3 numbers, got 2"),
    (CDPR.replace("exit_point: [-3.5, -2.0, 3.0]", "exit_point: [-3.5, x, 3.0]"),
     "cdpr.cables[0].exit_point[1]", "finite number"),
    (CDPR.replace("plant: cdpr", "plant: tower"), "plant", "unknown plant"),
    ("plant: crane\ncrane:\n  boom_length: -1\n", "crane.boom_length", "positive"),
    ("plant: axis\naxis:\n  joint_type: linear\n", "axis.joint_type", "revolute"),
    ("plant: axis\n", "axis", "missing"),
    ("plant: axis\naxis:\n  joint_type: prismatic\ncolour: red\n", "colour", "unknown key"),
    ("plant: [\n", "bad YAML", "line"),
])
def test_errors_name_the_key_path(text, key, what):
    msg = _err(text)
    assert msg.startswith(key) or key in msg, msg
    assert what in msg, msg


def test_missing_file_names_the_path(tmp_path):
    msg = _err(str(tmp_path / "nope.yaml"))
    assert "nope.yaml" in msg and "not found" in msg
    f = tmp_path / "d.yaml"
    f.write_text("plant: crane\ncrane: {boom_length: 1.0, boom_mas: 2}\n")
    msg = _err(str(f))
    assert str(f) in msg and "crane.boom_mas" in msg
