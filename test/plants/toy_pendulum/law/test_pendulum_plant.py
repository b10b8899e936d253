"""Tests of the pendulum plant (written by ``cablelab new-plant``, the closed form the pendulum's).

Oracles: the equilibrium and small-oscillation period of a torque-driven pendulum; the damping MuJoCo integrates against
the viscous friction ``cablelab diagnose`` identifies from a recorded run; the entry-point
discovery in a fresh interpreter."""
from __future__ import annotations

import json
import os
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest

HERE = Path(__file__).resolve().parent
DAMPING = 0.05   # N m s/rad, the truth the nominal model lacks


def plant_env(tmp_path: Path) -> dict:
    """Environment in which the package is installed: PYTHONPATH with it and a dist-info that
    announces its entry point (what ``pip install -e .`` would write)."""
    site = tmp_path / "site"
    dist = site / "pendulum_plant-0.1.0.dist-info"
    dist.mkdir(parents=True)
    (dist / "METADATA").write_text("Metadata-Version: 2.1\nName: pendulum-plant\nVersion: 0.1.0\n")
    (dist / "entry_points.txt").write_text("[cablelab.plants]\npendulum = pendulum_plant\n")
    path = os.pathsep.join([str(HERE), str(site), os.environ.get("PYTHONPATH", "")])
    return {**os.environ, "PYTHONPATH": path.rstrip(os.pathsep)}


def section():
    from cablelab.description import load_description

    return load_description(HERE / "pendulum_plant" / "data" / "pendulum.yaml").pendulum


def test_registered_through_the_entry_point(tmp_path):
    code = ("from cablelab.registry import available_plants, get_plant; "
            "p = get_plant('pendulum'); print(p.name in available_plants(), p.package)")
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True,
                         env=plant_env(tmp_path), check=True).stdout.split()
    assert out == ["True", "pendulum_plant"]


def test_description_section_round_trip_and_one_line_errors():
    from cablelab.errors import CablelabError
    from pendulum_plant.description import dump_section, parse_section

    sec = section()
    assert parse_section(dump_section(sec)) == sec
    with pytest.raises(CablelabError) as err:
        parse_section({"mass": 0.5, "length": -1.0})
    assert "length" in str(err.value) and "\n" not in str(err.value)


def test_simulator_follows_the_closed_form():
    """Constant torque on the undamped pendulum: it comes to rest (on average) at the angle where
    gravity balances the torque, m g l sin q = tau, and swings about it with the small-oscillation
    period 2 pi sqrt(l / (g cos q*)) of the linearised pendulum."""
    from pendulum_plant.sim import simulate

    sec, tau, g = section(), 0.2, 9.81
    q_eq = np.arcsin(tau / (sec.mass * g * sec.length))
    run = simulate(sec, 20.0, 1000.0, lambda t: tau)
    q = run["q"][1:]
    assert abs(q.mean() - q_eq) < 0.02 * q_eq
    up = np.flatnonzero((q[:-1] < q_eq) & (q[1:] >= q_eq))        # upward crossings of q_eq
    period = np.mean(np.diff(run["t"][1:][up]))
    assert period == pytest.approx(2 * np.pi * np.sqrt(sec.length / (g * np.cos(q_eq))), rel=0.02)


def test_diagnose_finds_the_hidden_damping(tmp_path):
    """A run with hinge damping, recorded as a bag: ``cablelab diagnose`` ranks viscous joint
    friction first, with the damping MuJoCo integrated."""
    from pendulum_plant.control import chirp
    from pendulum_plant.sim import simulate, write_bag

    text = (HERE / "pendulum_plant" / "data" / "pendulum.yaml").read_text()
    run = simulate(section(), 8.0, 200.0, lambda t: chirp(t, 8.0), damping=DAMPING)
    bag = tmp_path / "run"
    write_bag(bag, run, text, torque_noise=0.01)
    res = subprocess.run([sys.executable, "-m", "cablelab.cli", "diagnose", str(bag), "--json"],
                         capture_output=True, text=True, env=plant_env(tmp_path), timeout=300)
    assert res.returncode == 0, res.stderr
    out = json.loads(res.stdout)
    top = out["ranking"][0]
    assert out["plant"] == "pendulum" and top["effect"] == "joint_viscous_friction", out["ranking"]
    assert top["params"]["Fv"] == pytest.approx(DAMPING, rel=0.15)
