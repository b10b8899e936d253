"""``cablelab new-plant NAME [-o DIR]`` writes the plant template: the file of every role in its
place (docs/architecture.md, "The plant template"), a package that registers through its entry
point and whose generated tests pass (they check the skeleton's simulator against a closed form
and ``cablelab diagnose`` against the damping MuJoCo integrated); it never overwrites.

The toy plant (test/plants/toy_pendulum) is built from that skeleton plus its own law
(test_toy_plant.py)."""
from __future__ import annotations

import os
import subprocess
import sys

from cablelab.cli import main


#: the template's files: each role in its place (docs/architecture.md)
ROLES = ["__init__.py", "plant.py", "description.py", "dataset.py", "effects.py", "control.py",
         "mjcf.py", "sim.py", "topics.py", "demo.py", "nodes/__init__.py", "nodes/parameters.py",
         "nodes/sim.py", "nodes/estimator.py", "nodes/controller.py", "README.md", "data/{name}.yaml"]


def test_new_plant_writes_a_working_package(tmp_path, capsys):
    out = tmp_path / "winch_rig"
    assert main(["new-plant", "winch_rig", "-o", str(out)]) == 0
    package = out / "winch_rig_plant"
    for rel in ROLES:
        assert (package / rel.format(name="winch_rig")).is_file(), rel
    assert (out / "test_winch_rig_plant.py").is_file() and (out / "pyproject.toml").is_file()
    assert '[project.entry-points."cablelab.plants"]\nwinch_rig = "winch_rig_plant"' in \
        (out / "pyproject.toml").read_text()
    assert "/winch_rig/joint_states" in (package / "topics.py").read_text()
    capsys.readouterr()

    # the generated tests pass as written (registration through the entry point included)
    res = subprocess.run([sys.executable, "-m", "pytest", "-q", "-p", "no:cacheprovider", str(out)],
                         capture_output=True, text=True, cwd=out, timeout=600,
                         env={**os.environ, "PYTHONPATH": os.pathsep.join(
                             p for p in (str(out), os.environ.get("PYTHONPATH", "")) if p)})
    assert res.returncode == 0, res.stdout[-3000:] + res.stderr[-2000:]
    assert "4 passed" in res.stdout

    # the package imports and registers in a fresh interpreter; the node modules load
    code = ("import winch_rig_plant, winch_rig_plant.nodes.sim as s, winch_rig_plant.nodes.estimator, "
            "winch_rig_plant.nodes.controller; from cablelab.registry import get_plant; "
            "print(get_plant('winch_rig').joint_topic, len(s.PARAMETERS) > 0)")
    res = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, timeout=120,
                         env={**os.environ, "PYTHONPATH": str(out)})
    assert res.returncode == 0, res.stderr
    assert res.stdout.split() == ["/winch_rig/joint_states", "True"]


def test_new_plant_refuses_an_existing_directory_and_a_bad_name(tmp_path, capsys):
    out = tmp_path / "rig"
    out.mkdir()
    (out / "keep.txt").write_text("mine")
    assert main(["new-plant", "rig", "-o", str(out)]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and "already exists" in err[0] and str(out) in err[0]
    assert sorted(p.name for p in out.iterdir()) == ["keep.txt"]      # nothing written
    for bad in ("Rig", "2rig", "my-rig", "class"):
        assert main(["new-plant", bad, "-o", str(tmp_path / "x")]) == 2
        err = capsys.readouterr().err.strip().splitlines()
        assert len(err) == 1 and "plant name" in err[0]
    assert not (tmp_path / "x").exists()
