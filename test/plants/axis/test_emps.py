"""Proof on real data: the EMPS drive (../shared/data/emps/README.md).

Oracle: the published IDIM-LS reference model M = 95.1089 kg, Fv = 203.5034 N s/m,
Fc = 20.3935 N, OF = -3.1648 N, and the README's error ladder 18 % -> 7 % -> 4 %.
"""
import json
from pathlib import Path

import numpy as np
import pytest
import scipy.io

from cablelab.cli import main

ROOT = Path(__file__).resolve().parents[3]
BAG = ROOT / "bags" / "emps"
MAT = Path("/work/shared/data/emps/DATA_EMPS.mat")
PUBLISHED = {"M": 95.1089, "Fv": 203.5034, "Fc": 20.3935, "OF": -3.1648}
DESCRIPTION = "{plant: axis, name: EMPS, axis: {joint_type: prismatic}}"


def _json(capsys, argv):
    assert main(argv) == 0
    out = capsys.readouterr().out
    return json.loads(out)


def test_greedy_diagnosis_rediscovers_coulomb_then_offset_and_the_published_parameters(capsys):
    out = _json(capsys, ["diagnose", str(BAG), "--greedy", "--json"])
    assert out["plant"] == "axis"
    assert out["baseline"]["effects"] == ["axis_inertia", "joint_viscous_friction"]
    assert out["baseline"]["error"] == pytest.approx(0.18, abs=0.01)  # README: about 18 %
    rank = out["ranking"]
    assert rank[0]["effect"] == "joint_coulomb_friction" and rank[0]["significant"]
    errs = [r["error_after"] for r in rank]
    assert errs == sorted(errs)
    assert sum(r["significant"] for r in rank) == 1
    steps = out["greedy"]
    # with the zero-speed zone excluded, a sub-sample lead of the force command (the
    # controller's zero-order hold, about half a 1 ms sample) is significant after the two
    added = [s["added"] for s in steps]
    assert added[:3] == [None, "joint_coulomb_friction", "torque_sensor_offset"]
    assert added[3:] in ([], ["time_delay"])
    if added[3:]:
        assert -1e-3 < out["final"]["params"]["tau"] < 0
    assert steps[1]["error"] == pytest.approx(0.07, abs=0.01)  # README: about 7 %
    second = steps[1]["ranking"][0]
    assert second["effect"] == "torque_sensor_offset" and second["significant"]
    final = out["final"]
    assert final["effects"] == ["axis_inertia", "joint_viscous_friction", "joint_coulomb_friction",
                                "torque_sensor_offset"] + added[3:]
    assert final["error"] == pytest.approx(0.04, abs=0.008)  # README: about 4 %, held out
    for k, v in PUBLISHED.items():
        assert final["params"][k] == pytest.approx(v, rel=0.02), k
    # the last ranking shows nothing else is worth adding
    assert not any(r["significant"] for r in steps[-1]["ranking"])


def test_identify_and_compare_on_emps(capsys):
    ident = _json(capsys, ["identify", str(BAG), "--effects", "joint_coulomb_friction,torque_sensor_offset",
                           "--json"])
    p = ident["params"]
    for k, v in PUBLISHED.items():
        assert p[k]["value"] == pytest.approx(v, rel=0.02)
        # the autocorrelation-corrected standard errors cover the published (independent IDIM)
        # estimates within 3 sigma; the white-noise LS ones would not (Fc is 3.2 white sigma off)
        assert 0 < p[k]["stderr"] < 0.05 * abs(v)
        assert abs(p[k]["value"] - v) < 3 * p[k]["stderr"], k
    assert p["M"]["unit"] == "kg" and p["Fv"]["unit"] == "N s/m"
    assert ident["fit"]["rank"] == 4 and ident["fit"]["unidentifiable"] == []
    # the zero-speed zone (1.8 % of EMPS) is not fitted: 4.1 % instead of 4.4 %
    assert ident["fit"]["nrmse"] == pytest.approx(0.041, abs=0.003)
    cmp_ = _json(capsys, ["compare", str(BAG), "--json"])
    ch = cmp_["joint"]
    assert set(ch) >= {"nrmse", "pearson", "mae", "max_abs"}
    assert ch["nrmse"] == pytest.approx(0.18, abs=0.01)
    assert cmp_["channels"]["joint"] == ch
    seg = cmp_["worst_segments"]
    assert len(seg) == 5 and all(s["channel"] == "joint" and s["t_end"] > s["t_start"] for s in seg)
    assert seg[0]["error"] >= seg[-1]["error"]
    # free run (MuJoCo, driven by the measured force): the identified friction and offset make
    # the simulated motion follow the real one several times more closely
    full = _json(capsys, ["compare", str(BAG), "--effects", "joint_coulomb_friction,torque_sensor_offset",
                          "--json"])
    assert full["free_run"]["nrmse"] < 0.05 < cmp_["free_run"]["nrmse"]
    assert full["joint"]["nrmse"] == pytest.approx(0.041, abs=0.003)  # zero-speed zone not fitted


@pytest.mark.skipif(not MAT.exists(), reason="EMPS data set not present")
def test_import_writes_the_committed_bag_from_the_mat_file(tmp_path, capsys):
    out = tmp_path / "emps"
    info = _json(capsys, ["import", str(MAT), "--plant", "axis", "--map",
                          "time=t,position=qm,effort=gtau*vir", "--description", DESCRIPTION,
                          "-o", str(out), "--json"])
    assert info["samples"] == 24841
    from cablelab.bags import open_bag

    mat = scipy.io.loadmat(str(MAT))
    for path in (out, BAG):
        bag = open_bag(path)
        js = bag.joint_state("/axis/joint_states")
        assert js.names == ["joint"]
        assert np.allclose(js.effort[:, 0], mat["gtau"].item() * mat["vir"].ravel(), rtol=0, atol=1e-9)
        assert np.allclose(js.position[:, 0], mat["qm"].ravel(), rtol=0, atol=1e-12)
        assert np.all(np.isnan(js.velocity))
        assert np.allclose(js.t, mat["t"].ravel(), atol=1e-8)
        assert bag.description.plant == "axis"
