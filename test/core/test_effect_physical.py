"""Parameters in the user's terms: every registered effect reports parameters named as the
description, the spec or the paper name them, each with a unit (checked against the table in
docs/workbench.md, which is the user's reference), never an internal regression coefficient;
their standard errors are the delta method's (checked against the closed form and a Monte Carlo
of the same covariance)."""
import re
from pathlib import Path

import numpy as np
import pytest

from cablelab.dataset import Dataset
from cablelab.effects import all_effects
from cablelab.fit.identification import propagate

DOC = Path(__file__).resolve().parents[2] / "docs" / "workbench.md"
#: coefficients of the regression that are not what a user knows (paper / spec names replace them)
INTERNAL = {"c_td", "c_lo", "dm_f", "off_x", "off_y", "off_yaw", "dFs", "vs_rel", "mx", "my",
            "c_x", "c_y"}


def _doc_table() -> dict:
    text = DOC.read_text()
    sec = text.split("## Parameters in the user's terms", 1)[1].split("\n## ", 1)[0]
    rows = {}
    for m in re.finditer(r"^\| `(\w+)` \| (.+) \|$", sec, re.M):
        rows[m.group(1)] = [tuple(x.strip().rstrip(")").split(" (", 1)) for x in m.group(2).split("),")]
    return rows


def _dataset():
    n = 200
    rng = np.random.default_rng(0)
    return Dataset(plant="x", t=np.arange(n) * 0.01, y=np.zeros((n, 1)), channels=("c",),
                   signals={"L": 1.0, "g": 9.81}, actuators=("a",), act_vel=rng.normal(size=(n, 1)),
                   act_units=(("N", "m"),))


def _reported(effect, ds):
    if effect.physical is not None:
        return [(p.name, p.unit, p.doc) for p in effect.physical(ds)]
    return [(p.name, p.unit, p.doc) for p in list(effect.columns(ds)) + list(effect.nonlinear)]


def test_every_registered_effect_reports_named_parameters_with_units():
    ds = _dataset()
    table = _doc_table()
    from cablelab.registry import available_plants

    # the product's effects (toy effects other tests register for unregistered plants aside)
    plants = set(available_plants()) | {"*"}
    effects = {k: e for k, e in all_effects().items() if plants & set(e.plants)}
    assert set(table) == set(effects), set(table) ^ set(effects)
    fill = {"effort": "N", "position": "m", "inertia": "kg"}
    for eid, eff in effects.items():
        got = _reported(eff, ds)
        assert got, eid
        documented = [(n, u.format(**fill)) for n, u in table[eid]]
        assert [(n, u) for n, u, _ in got] == documented, eid
        for name, unit, doc in got:
            assert unit and "{" not in unit, (eid, name)
            assert doc, (eid, name)                       # says what it is and where it comes from
            assert name not in INTERNAL, (eid, name)


def test_delta_method_matches_the_closed_form_and_a_monte_carlo():
    # beta = 1 - c / m with correlated (c, m): var = g C g^T, g = (-1/m, c/m^2)
    c, m = 0.66, 1.55
    cov = np.array([[1.4e-5, 0.6e-5], [0.6e-5, 3.6e-5]])
    value, se = propagate(lambda p: 1.0 - p["c"] / p["m"], {"c": c, "m": m, "k": 605.0},
                          ("c", "m"), cov)
    g = np.array([-1.0 / m, c / m**2])
    assert value == pytest.approx(1 - c / m, rel=1e-12)
    assert se == pytest.approx(np.sqrt(g @ cov @ g), rel=1e-6)
    draws = np.random.default_rng(4).multivariate_normal([c, m], cov, size=200000)
    assert se == pytest.approx(np.std(1.0 - draws[:, 0] / draws[:, 1]), rel=0.02)
    # a parameter outside the covariance (fixed) is exact
    _, se_fixed = propagate(lambda p: p["c"] / p["k"], {"c": c, "m": m, "k": 605.0}, ("c", "m"), cov)
    assert se_fixed == pytest.approx(np.sqrt(cov[0, 0]) / 605.0, rel=1e-6)
