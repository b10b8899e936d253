"""``excite.design`` for the model the designed run will be fitted with (``effects``, ``fixed``):
the design's model carries the further effects and the known parameters, and its condition
numbers are those of that model.

Oracles: the condition number recomputed on the designed motion with the model built here
(:func:`cablelab.excite.condition`), and the Schur complement's monotonicity: a known parameter
has no column to eliminate, so the named parameters' condition number with it fixed can only be
lower than (or equal to) the one with it free, on the same motion."""
from pathlib import Path

import pytest

import cablelab.plants.crane as crane_pkg
from cablelab import excite as E
from cablelab.description import load_description
from cablelab.errors import CablelabError
from cablelab.model import Model

DESC = load_description(str(Path(crane_pkg.__file__).parent / "data" / "crane.yaml"))
PAIR = ["OF[hoist]", "m"]
KNOWN = {"m_b": DESC.crane.boom_mass, "m_c": DESC.crane.counterbalance.mass,
         "l_c": DESC.crane.counterbalance.distance}


@pytest.fixture(scope="module")
def designed():
    return E.design("crane", DESC, PAIR, duration=20.0, seed=3, max_iter=3,
                    effects=("joint_viscous_friction",), fixed=KNOWN)


def test_design_uses_the_fitted_model(designed):
    d = designed
    assert "joint_viscous_friction" in d.model.effects and "torque_sensor_offset" in d.model.effects
    assert dict(d.model.fixed) == KNOWN
    ex = E.get_exciter("crane")
    ds = ex.motion_dataset(d.t, d.q, d.qd, d.qdd, DESC)
    fitted = Model("crane", d.model.effects, KNOWN)
    assert d.condition_after == pytest.approx(E.condition(fitted, ds, PAIR), rel=1e-9)
    # the same motion with the boom and counterbalance unknown: more to eliminate, never better
    free = Model("crane", d.model.effects, {})
    assert E.condition(free, ds, PAIR) >= d.condition_after * (1 - 1e-9)
    assert d.limits.check(d.q, d.qd, d.qdd) == []


def test_named_parameter_cannot_be_fixed():
    with pytest.raises(CablelabError, match="also fixed"):
        E.design("crane", DESC, PAIR, duration=20.0, max_iter=1, fixed={"m": 0.5})
