"""The axis controller plays a designed reference (``reference_bag``) over DDS: what it publishes
on /axis/reference is the bag's trajectory, and the simulated axis follows it."""
from __future__ import annotations

import sys

import numpy as np

from cablelab.description import load_description
from cablelab.excite import design, get_exciter, read_reference, write_reference
from cablelab.plants.axis.nodes.sim import DEFAULT_DESCRIPTION


def test_axis_controller_plays_the_reference_bag(launcher, tmp_path):
    from cablelab.bags import open_bag

    desc = load_description(DEFAULT_DESCRIPTION)
    d = design("axis", desc, ["Fc", "OF"], duration=12.0, max_iter=5)
    ref = tmp_path / "ref"
    write_reference(ref, d, get_exciter("axis"), DEFAULT_DESCRIPTION)
    bag_dir = tmp_path / "run"
    launcher.start("recorder", [sys.executable, "-m", "cablelab.cli", "record", "--plant", "axis",
                                "-o", bag_dir, "--quiet"])
    launcher.wait_for_subscribers(["/axis/joint_states", "/axis/reference"], timeout=120,
                                  node_name="cablelab_recorder")
    launcher.node("sim", "cable_sim_node", "axis", {"rate": 200.0, "lockstep": True,
                                                    "wait_for_subscribers": 2})
    launcher.node("controller", "pd_feedforward", "axis", {"reference_bag": str(ref)})
    launcher.wait_for_recorded(bag_dir, {"/axis/joint_states": 1000, "/axis/reference": 900,
                                         "/plant_description": 1}, timeout=180)
    codes = launcher.stop_all()
    assert codes == {"controller": 0, "sim": 0, "recorder": 0}, codes
    bag = open_bag(bag_dir)
    played = bag.joint_trajectory("/axis/reference", ["joint"])
    # the published reference is the bag's trajectory at the controller's clock since its start
    tt = played.t - played.t[0]
    want = read_reference(ref, "/axis/reference", ["joint"])(tt)[0]
    np.testing.assert_allclose(played.positions, want, atol=1e-6)
    # and the axis follows it (PD + feedforward: within a tenth of the designed stroke after 1 s)
    js = bag.joint_state("/axis/joint_states", ["joint"])
    late = tt > 1.0
    q = np.interp(played.t[late], js.t, js.position[:, 0])
    stroke = np.ptp(played.positions[:, 0])
    assert stroke > 0.05
    assert np.max(np.abs(q - played.positions[late, 0])) < 0.1 * stroke
