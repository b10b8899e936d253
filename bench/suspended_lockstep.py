"""The LiCAS closed loop through DDS with and without lock-step: simulator (truth
plant, arm torque motors, 1 kHz), controller (PD + gravity, 000 Fig. 7 y excitation) and recorder
as separate processes on their own ROS_DOMAIN_ID, 3 s simulated from a pushed start
(swing_x = 0.05 rad). Without lock-step the commands arrive late (the 1 kHz loop through Python
and DDS takes longer than 1 ms on this machine) and the stiff arm joints (k_d / I ~ 1000 1/s)
diverge; with it every command answers the state it is applied after.

    nice -n 10 ./run python bench/suspended_lockstep.py [--json]

Columns: ``max_qd`` the largest recorded arm joint speed (rad/s), ``max_tau`` the largest
recorded torque (N m; the LiCAS limit is 10), ``track_err`` the largest deviation of the arm
joints from the Fig. 7 reference after 0.5 s (rad), ``wall_s`` the simulator's wall time
(start-up included).
"""
from __future__ import annotations

import sys
import tempfile
import time
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parent))
from harness import Bench  # noqa: E402

from cablelab.bags import open_bag  # noqa: E402
from cablelab.plants.suspended.control import fig7_excitation  # noqa: E402
from cablelab.plants.suspended.params import parameter_set  # noqa: E402
from cablelab.ros.launch import Launcher  # noqa: E402


def run(lockstep: bool, duration: float = 3.0) -> dict:
    tmp = Path(tempfile.mkdtemp(prefix="suspended-lockstep-"))
    bag_dir = tmp / "run"
    with Launcher(log_dir=tmp / "logs") as launch:
        launch.start("recorder", [sys.executable, "-m", "cablelab.cli", "record", "--plant", "suspended",
                                  "-o", bag_dir, "--quiet"])
        launch.node("controller", "pd_feedforward", "suspended",
                    {"excitation": "'y'", "excitation_level": 1, "pose_sync": lockstep})
        launch.wait_for_subscribers(["/suspended/joint_states"], timeout=120, node_name="cablelab_recorder")
        launch.wait_for_subscribers(["/suspended/joint_states"], timeout=120, node_name="pd_feedforward")
        t0 = time.monotonic()
        sim = launch.node("sim", "cable_sim_node", "suspended",
                          {"model": "truth", "arm_input": "effort", "lockstep": lockstep, "rate": 1000.0,
                           "wait_for_subscribers": 2, "duration": duration, "start_swing_x": 0.05})
        sim.wait(600)
        wall = time.monotonic() - t0
        time.sleep(2.0)
        launch.stop_all()
    js = open_bag(bag_dir, recover=True).joint_state("/suspended/joint_states")
    _, first = np.unique(js.t, return_index=True)
    t, q = js.t[first], js.position[first]
    ref, _ = fig7_excitation(t, parameter_set("licas"), "y", 1)
    late = t > 0.5
    return {"lockstep": lockstep, "states": len(t), "max_qd": float(np.nanmax(np.abs(js.velocity))),
            "max_tau": float(np.nanmax(np.abs(js.effort))),
            "track_err": float(np.nanmax(np.abs(q[late] - ref[late]))), "wall_s": wall}


def main() -> None:
    bench = Bench("suspended_lockstep", __doc__)
    bench.parse()
    bench.section("closed loop over DDS, 3 s simulated")
    for lockstep in (True, False):
        bench.row(**run(lockstep))
    bench.done()


if __name__ == "__main__":
    main()
