"""A plant written in one folder (``cablelab new-plant pendulum`` plus its law, :mod:`toy`) is found through the
``cablelab.plants`` entry-point group and works end to end with no edit outside its folder:
``cable_sim_node --plant pendulum`` simulates it, ``cablelab record --plant pendulum`` records it,
``cablelab diagnose`` finds the hidden hinge damping and ``cablelab report`` renders the report.

Oracle: the damping MuJoCo integrates (``damping`` parameter of the simulator) against the
viscous-friction coefficient the diagnosis identifies from the recorded bag."""
from __future__ import annotations

import json
import os
import subprocess
import sys
from pathlib import Path

import pytest

from toy import LAW, build, toy_dir
DAMPING = 0.05  # N m s/rad, hidden from the nominal model


def plant_env(tmp_path: Path) -> dict:
    """PYTHONPATH with the toy package and a dist-info that announces it as entry point."""
    site = tmp_path / "site"
    dist = site / "toy_pendulum-0.1.dist-info"
    dist.mkdir(parents=True)
    (dist / "METADATA").write_text("Metadata-Version: 2.1\nName: toy-pendulum\nVersion: 0.1\n")
    (dist / "entry_points.txt").write_text("[cablelab.plants]\npendulum = pendulum_plant\n")
    path = os.pathsep.join([str(toy_dir()), str(site), os.environ.get("PYTHONPATH", "")])
    return {"PYTHONPATH": path.rstrip(os.pathsep)}


def cli(env: dict, *args: str) -> subprocess.CompletedProcess:
    return subprocess.run([sys.executable, "-m", "cablelab.cli", *args], capture_output=True,
                          text=True, env={**os.environ, **env}, timeout=300)


def test_plant_package_outside_cablelab_is_discovered(tmp_path):
    env = plant_env(tmp_path)
    code = ("from cablelab.registry import available_plants, get_plant; "
            "print(available_plants(), get_plant('pendulum').package)")
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True,
                         env={**os.environ, **env}, check=True).stdout
    assert "'pendulum'" in out and "pendulum_plant" in out
    # without the entry point, the plant is unknown (nothing else names it)
    bad = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True)
    assert bad.returncode != 0 and "pendulum" in bad.stderr


def test_toy_plant_simulated_recorded_diagnosed_reported(launcher, tmp_path):
    env = plant_env(tmp_path)
    launcher.env.update(env)
    bag = tmp_path / "pendulum_run"
    launcher.start("recorder", [sys.executable, "-m", "cablelab.cli", "record", "--plant",
                                "pendulum", "-o", bag, "--quiet"])
    launcher.wait_for_subscribers(["/pendulum/joint_states"], timeout=120,
                                  node_name="cablelab_recorder")
    launcher.node("sim", "cable_sim_node", "pendulum",
                  {"damping": DAMPING, "duration": 8.0, "wait_for_subscribers": 1})
    launcher.wait_for_recorded(bag, {"/pendulum/joint_states": 1600, "/plant_description": 1},
                               timeout=240)
    # the simulator ends by itself after `duration` s of simulated time (exit 0); only then is
    # the recorder stopped (a stop signal racing the sim's own exit would not test the plant)
    assert launcher.procs["sim"].wait(120) == 0, launcher.procs["sim"].log()[-2000:]
    codes = launcher.stop_all()
    assert codes["recorder"] == 0, codes

    res = cli(env, "diagnose", str(bag), "--json")
    assert res.returncode == 0, res.stderr
    out = json.loads(res.stdout)
    assert out["plant"] == "pendulum"
    assert out["baseline"]["effects"] == ["pendulum_inertia", "pendulum_gravity"]
    top = out["ranking"][0]
    assert top["effect"] == "joint_viscous_friction" and top["significant"], out["ranking"]
    assert top["params"]["Fv"] == pytest.approx(DAMPING, rel=0.15)

    report = tmp_path / "report"
    res = cli(env, "report", str(bag), "-o", str(report))
    assert res.returncode == 0, res.stderr
    html = (report / "index.html").read_text()
    assert "joint_viscous_friction" in html and list(report.glob("*.png"))


def test_toy_plant_is_the_template_plus_its_law_and_its_tests_pass(tmp_path):
    """Every file of the law differs from what the template writes (the rest is the template's,
    by construction, its tests included), and the template's tests pass on the built package
    (with the pendulum's closed form, ``closed_form.py``: equilibrium angle and small-oscillation
    period)."""
    from cablelab.plant_template import plant_files

    template = plant_files("pendulum")
    law = [str(p.relative_to(LAW)) for p in LAW.rglob("*") if p.is_file() and "__pycache__" not in p.parts]
    assert law and all(rel in template and (LAW / rel).read_text() != template[rel] for rel in law), law
    out = build(tmp_path / "toy")
    res = subprocess.run([sys.executable, "-m", "pytest", "-q", "-p", "no:cacheprovider", str(out)],
                         capture_output=True, text=True, cwd=out, timeout=600,
                         env={**os.environ, "PYTHONPATH": os.pathsep.join(
                             p for p in (str(out), os.environ.get("PYTHONPATH", "")) if p)})
    assert res.returncode == 0, res.stdout[-3000:] + res.stderr[-2000:]
    assert " passed" in res.stdout and "failed" not in res.stdout
