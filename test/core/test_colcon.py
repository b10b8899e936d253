"""The ROS workspace: colcon builds the four ament_python packages into a temporary directory,
installs the node executables where `ros2 run` looks (install/<pkg>/lib/<pkg>/<exe>) and they run;
`cd ros_ws && colcon build` discovers the packages through the src symlink."""
from __future__ import annotations

import os
import shutil
import subprocess
import sys
from pathlib import Path

ROOT = Path(__file__).resolve().parents[2]
PACKAGES = ("cablelab", "cable_sim_node", "payload_estimator", "pd_feedforward")


def _colcon() -> str:
    exe = shutil.which("colcon") or str(Path(sys.executable).parent / "colcon")
    assert Path(exe).exists(), "colcon not installed in the environment"
    return exe


def test_colcon_build_installs_runnable_executables(tmp_path):
    out = subprocess.run([_colcon(), "--log-base", str(tmp_path / "log"), "build",
                          "--base-paths", str(ROOT / "ros_ws" / "src"),
                          "--build-base", str(tmp_path / "build"),
                          "--install-base", str(tmp_path / "install")],
                         cwd=tmp_path, capture_output=True, text=True, timeout=600)
    assert out.returncode == 0, out.stdout[-2000:] + out.stderr[-2000:]
    assert "4 packages finished" in out.stdout, out.stdout[-2000:]
    site = [str(p) for p in (tmp_path / "install").glob("*/lib/python3*/site-packages")]
    env = {**os.environ, "PYTHONPATH": os.pathsep.join(site)}
    for pkg, exe in (("cable_sim_node", "cable_sim_node"), ("payload_estimator", "payload_estimator"),
                     ("pd_feedforward", "pd_feedforward"), ("pd_feedforward", "control_loop"),
                     ("cablelab", "cablelab")):
        path = tmp_path / "install" / pkg / "lib" / pkg / exe
        assert path.exists(), f"{path} not installed"
        res = subprocess.run([str(path), "--help"], capture_output=True, text=True, env=env, timeout=120)
        assert res.returncode == 0, res.stderr
        assert "usage:" in res.stdout and ("--plant" in res.stdout or exe == "cablelab")
        # ament index marker so `ros2 run` / `ros2 pkg list` see the package
        assert (tmp_path / "install" / pkg / "share" / "ament_index" / "resource_index" / "packages" / pkg).exists()


def test_workspace_discovers_packages_through_src_symlink():
    assert (ROOT / "ros_ws" / "src").is_symlink()
    out = subprocess.run([_colcon(), "list", "--names-only"], cwd=ROOT / "ros_ws",
                         capture_output=True, text=True, timeout=120)
    assert out.returncode == 0, out.stderr
    assert sorted(out.stdout.split()) == sorted(PACKAGES)
