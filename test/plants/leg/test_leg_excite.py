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

import cablelab.plants.leg as leg_pkg
from cablelab.cli import main
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
