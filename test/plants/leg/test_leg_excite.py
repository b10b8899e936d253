"""``cablelab excite`` on the hopping leg: low hops confound the spring preload F0 with the mass
m (the stance force ``m (zdd + g) - F0`` is nearly one column when every stance looks alike);
the designed apex-height schedule, played by the apex-height controller on the hybrid MuJoCo
leg, keeps the leg inside its limits (apexes in the designed range, torque within T_max, the
body above the crouch the spring allows) and a fit on that run finds both where the low hops'
fit did not.

Oracle: the hybrid MuJoCo leg (plants/leg/sim.py) with a hidden 2.7 N preload, under the live
estimator and the apex controller (plants/leg/excite.py ``closed_loop``)."""
import json
from pathlib import Path

import numpy as np
import pytest
from hypothesis import given, settings, strategies as st

import cablelab.plants.leg as leg_pkg
from cablelab.cli import main
from cablelab.description import load_description
from cablelab.excite import get_exciter, read_reference
from cablelab.fit import identify
from cablelab.plants.leg.control import ApexController
from cablelab.plants.leg.excite import closed_loop
from cablelab.plants.leg.hybrid import LegParams
from cablelab.plants.leg.sim import write_bag
from cablelab.plants.leg.strides import apexes
from cablelab.plants.leg.topics import REFERENCE
from cablelab.workbench import build_model, load

DESC = (Path(leg_pkg.__file__).parent / "data" / "leg.yaml").read_text()
NOMINAL = LegParams()
TRUTH = NOMINAL.replace(F0=2.7)
LOW = NOMINAL.z_td + 0.004


@pytest.fixture(scope="module")
def low_hops(tmp_path_factory):
    path = tmp_path_factory.mktemp("leg_excite") / "low_hops"
    write_bag(path, closed_loop(TRUTH, LOW, 30.0, controller_params=NOMINAL), DESC)
    return str(path)


def test_designed_apex_schedule_separates_preload_and_mass(low_hops, tmp_path, capsys):
    plant, desc, ds = load(low_hops)
    model = build_model(plant, desc, ["impact_restitution", "spring_preload"])
    r0 = identify(model, ds)
    ref = tmp_path / "ref"
    assert main(["excite", low_hops, "--params", "F0,m", "--duration", "60", "-o", str(ref),
                 "--json"]) == 0
    out = json.loads(capsys.readouterr().out)
    print(f"leg F0,m condition number: before {out['condition_before']:.3g}, after "
          f"{out['condition_after']:.3g}; low hops F0 {r0.params['F0']:.3f} N, m {r0.params['m']:.4f} kg")
    assert out["params"] == ["F0", "m"] and out["duration"] == pytest.approx(60.0)
    assert out["condition_after"] < out["condition_before"] / 2
    # the controller plays the schedule on the hybrid leg: the apexes stay in the designed range
    lim = get_exciter("leg").limits(desc)
    play = read_reference(ref, REFERENCE, list(lim.joints))
    q_ref, qd_ref, qdd_ref = play(np.arange(0.0, 60.0, 0.01))
    assert lim.check(q_ref, qd_ref, qdd_ref) == []
    assert np.ptp(q_ref) > 0.004
    run = closed_loop(TRUTH, lambda t: play(t)[0][0, 0], 60.0, controller_params=NOMINAL)
    ap = apexes(run.t, run.z, run.contact)
    settled = ap[ap[:, 0] > 5.0]
    assert len(settled) > 50
    assert np.all(settled[:, 1] >= lim.lower[0] - 0.002) and np.all(settled[:, 1] <= lim.upper[0] + 0.002)
    assert np.abs(run.tau).max() <= ApexController.T_max + 1e-9              # torque limit
    assert run.z.min() > NOMINAL.z_td - 0.1 and run.z.max() < lim.upper[0] + 0.01
    # diagnosed on the run: both come back (the low hops' fit missed the preload)
    write_bag(tmp_path / "designed", run, DESC)
    _, _, ds2 = load(tmp_path / "designed")
    r = identify(model, ds2)
    assert r.params["F0"] == pytest.approx(2.7, abs=0.15)
    assert r.params["m"] == pytest.approx(TRUTH.m, rel=0.01)
    assert abs(r.params["F0"] - 2.7) < abs(r0.params["F0"] - 2.7)


@settings(max_examples=12, deadline=None)
@given(shares=st.lists(st.floats(0.0, 1.0), min_size=5, max_size=5).filter(lambda w: sum(w) > 1e-3),
       pair=st.sampled_from([("F0", "m"), ("F0", "dm_f"), ("k2", "k3"), ("c_td", "F0"), ("Fc", "d_s")]))
def test_design_dataset_gives_every_model_the_information_of_the_rows(shares, pair):
    """The design evaluates the triangular factors of the steady-hop levels' rows, not the rows:
    the condition number of any leg model (every candidate effect, fixed and free parameters) on
    a schedule equals the one on the row-by-row dataset (oracle: :func:`motion_rows`, the levels'
    rows themselves), while the factors hold a few rows per level."""
    from cablelab.effects import get_effect
    from cablelab.excite import condition
    from cablelab.model import Model
    from cablelab.plants.leg.excite import hop_library, motion_dataset, motion_rows

    desc = load_description(DESC)
    heights, dss = hop_library(desc)
    # a schedule spending the drawn time shares at the library heights (samples at the levels)
    counts = np.round(400 * np.asarray(shares) / sum(shares)).astype(int)
    q = np.repeat(heights, counts)
    t = np.arange(len(q)) * 0.1
    z = np.zeros_like(q)
    fixed = {"m": 1.55} if "dm_f" in pair else {}
    owners = {n: e for e in CANDIDATE_EFFECTS for n in [p.name for p in get_effect(e, "leg").params]}
    model = Model("leg", tuple(dict.fromkeys(("leg_inertia", "stance_damping", "flight_damping")
                                             + tuple(owners[n] for n in pair if n in owners))), fixed)
    rows, factors = motion_rows(t, q, z, z, desc), motion_dataset(t, q, z, z, desc)
    assert factors.n * 100 < rows.n                          # 15 rows per level instead of 2440
    assert condition(model, factors, pair) == pytest.approx(condition(model, rows, pair), rel=1e-8)
    assert condition(model, factors) == pytest.approx(condition(model, rows), rel=1e-8)


CANDIDATE_EFFECTS = ("leg_inertia", "stance_damping", "flight_damping", "impact_restitution", "spring_preload",
                     "spring_nonlinearity", "guide_coulomb_friction", "phase_effective_mass")
