"""`cablelab batch --strict` means what it means in diagnose/identify: a bag that does not excite
a parameter of the model (a slide moving at constant speed: its mass M is not in the data) is
diagnosed with M held at the description's value and a warning by default, and refused (its one
row's status is the refusal) with --strict; a bag that excites everything is the same either way.
"""
from __future__ import annotations

import json
import subprocess
import sys

import numpy as np
import pyarrow.parquet as pq
import pytest

from cablelab.bags import BagWriter
from cablelab.description import load_description
from cablelab.fleet.scan import BagRef
from cablelab.fleet.task import run_bag
from cablelab.plants.axis.sim import AxisTruth
from cablelab.plants.axis.truth import simulate_axis

DESC = "plant: axis\nname: {name}\naxis:\n  joint_type: prismatic\n  inertia: 2.0\n"


def _write(path, t, q, effort, name):
    path.parent.mkdir(parents=True, exist_ok=True)
    with BagWriter(path) as w:
        w.write_description(DESC.format(name=name))
        w.write_joint_states("/axis/joint_states", t, ["joint"], q[:, None], None, effort[:, None])
    return path


@pytest.fixture(scope="module")
def root(tmp_path_factory):
    root = tmp_path_factory.mktemp("fleet")
    t = np.arange(2000) * 0.01
    effort = 3.0 + 0.05 * np.random.default_rng(3).normal(size=t.size)   # 3 N at 0.1 m/s, noisy
    _write(root / "slow" / "run", t, 0.1 * t, effort, "slow")           # constant speed: M unexcited
    run = simulate_axis(load_description(DESC.format(name="moving")),
                        AxisTruth(inertia=2.0, viscous=5.0, coulomb=1.0),
                        duration=12.0, fs=250.0, amplitude=0.3, noise_effort=0.05, seed=1)
    _write(root / "moving" / "run", run.t, run.q, run.effort, "moving")
    return root


def _batch(root, out, *extra):
    p = subprocess.run([sys.executable, "-m", "cablelab.cli", "batch", str(root), "-o", str(out),
                        "--workers", "1", *extra], capture_output=True, text=True, timeout=600)
    assert p.returncode == 0, p.stderr[-3000:]
    return p.stdout, pq.read_table(out / "results.parquet").to_pylist()


def test_unexcited_parameter_held_with_a_warning_by_default(root, tmp_path):
    text, rows = _batch(root, tmp_path / "out")
    slow = [r for r in rows if r["bag"] == "slow/run"]
    assert slow and all(r["status"] == "ok" for r in slow)
    assert all("M" in r["warnings"] and "--strict" in r["warnings"] for r in slow)
    inertia = json.loads(next(r for r in slow if r["effect"] == "axis_inertia")["params"])
    assert inertia["M"]["held"] and inertia["M"]["value"] == pytest.approx(2.0)   # the description's
    # the rest is the fit with M known: 3 N at 0.1 m/s is all viscous friction
    fv = json.loads(next(r for r in slow if r["effect"] == "joint_viscous_friction")["params"])
    assert fv["Fv"]["value"] == pytest.approx(30.0, rel=0.01) and not fv["Fv"].get("held")
    moving = [r for r in rows if r["bag"] == "moving/run"]
    assert moving and all(r["status"] == "ok" and r["warnings"] is None for r in moving)
    assert "1 bags do not excite every parameter" in text and "--strict" in text
    js = subprocess.run([sys.executable, "-m", "cablelab.cli", "batch", str(root), "-o",
                         str(tmp_path / "out"), "--json"], capture_output=True, text=True, timeout=600)
    assert json.loads(js.stdout) == {"bags": 2, "failed": 0, "drift": [], "held": 1}


def test_strict_refuses_the_bag_that_does_not_excite_a_parameter(root, tmp_path):
    _, rows = _batch(root, tmp_path / "out", "--strict")
    slow = [r for r in rows if r["bag"] == "slow/run"]
    assert len(slow) == 1 and slow[0]["effect"] == ""
    status = slow[0]["status"]
    assert "rank-deficient" in status and "M" in status and "\n" not in status
    moving = [r for r in rows if r["bag"] == "moving/run"]
    assert moving and all(r["status"] == "ok" for r in moving)


def test_the_task_passes_strict_to_the_diagnosis(root):
    """The unit of work alone (no Dask): same rows as the command line."""
    ref = BagRef(str(root / "slow" / "run"), "slow/run")
    held = run_bag(ref, "h", strict=False)
    refused = run_bag(ref, "h", strict=True)
    assert {r["status"] for r in held} == {"ok"} and len(refused) == 1
    assert refused[0]["status"].startswith("rank-deficient")
