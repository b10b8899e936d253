"""The ``leg:`` description section: defaults file, parameters, one-line errors naming the key."""
from __future__ import annotations

from pathlib import Path

import pytest

import cablelab.plants.leg as leg_pkg
from cablelab.description import load_description
from cablelab.errors import CablelabError
from cablelab.plants.leg.description import leg_of, parse_section

DATA = Path(leg_pkg.__file__).parent / "data" / "leg.yaml"


def test_default_description_gives_spec_parameters():
    desc = load_description(DATA)
    assert desc.plant == "leg"
    p = leg_of(desc).params(desc.gravity)
    assert p.z_td == pytest.approx(0.28191, abs=1e-5)
    assert (p.m, p.k, p.d_s, p.d_f, p.beta_td, p.beta_lo) == (1.55, 605.0, 6.35, 1.18, 0.57, 1.13)
    assert p.spring_rest == p.z_td  # z_0 defaults to the free length (spec E2)


def test_missing_link_length_is_one_line_error_naming_the_key():
    text = DATA.read_text().replace("  link_length: 0.15", "")
    with pytest.raises(CablelabError) as exc:
        load_description(text)
    msg = str(exc.value)
    assert "leg.link_length" in msg and "missing required key" in msg and "\n" not in msg


@pytest.mark.parametrize("section, key", [
    ({"spring_stiffness": 605.0, "link_length": 0.15, "spring": 1.0}, "leg.spring"),
    ({"spring_stiffness": -1.0, "link_length": 0.15}, "leg.spring_stiffness"),
    ({"spring_stiffness": 605.0, "link_length": "long"}, "leg.link_length"),
    ({"spring_stiffness": 605.0, "link_length": 0.15, "spring_rest": 0.4}, "leg.spring_rest"),
    ({"spring_stiffness": 605.0, "link_length": 0.15, "free_angle": 2.0}, "leg.free_angle"),
])
def test_bad_values_name_the_key(section, key):
    with pytest.raises(CablelabError, match=key.replace(".", r"\.")):
        parse_section(section)


def test_plant_leg_without_section_is_an_error():
    with pytest.raises(CablelabError, match="^leg: missing required key"):
        load_description("plant: leg\n")
