"""The crane controller plays a designed reference (``reference_bag``) over DDS: what it
publishes on /crane/reference is the bag's trajectory, and the simulated crane follows it."""
from __future__ import annotations

import sys
from pathlib import Path

import numpy as np

import cablelab.plants.crane as crane_pkg
from cablelab.description import load_description
from cablelab.excite import design, get_exciter, read_reference, write_reference


def test_controller_plays_the_reference_bag(launcher, tmp_path):
    from cablelab.bags import open_bag

    desc_text = (Path(crane_pkg.__file__).parent / "data" / "crane.yaml").read_text()
    desc = load_description(desc_text)
    d = design("crane", desc, ["OF[luff]", "m_c"], duration=12.0, max_iter=5)
    ref = tmp_path / "ref"
    write_reference(ref, d, get_exciter("crane"), desc_text)
    bag_dir = tmp_path / "run"
    launcher.start("recorder", [sys.executable, "-m", "cablelab.cli", "record", "--plant", "crane",
                                "-o", bag_dir, "--quiet"])
    launcher.wait_for_subscribers(["/crane/joint_states", "/crane/reference"], timeout=120,
                                  node_name="cablelab_recorder")
    launcher.node("sim", "cable_sim_node", "crane", {"rate": 100.0, "wait_for_subscribers": 2})
    launcher.node("controller", "pd_feedforward", "crane", {"reference_bag": str(ref)})
    launcher.wait_for_recorded(bag_dir, {"/crane/joint_states": 800, "/crane/reference": 600,
                                         "/plant_description": 1}, timeout=180)
    codes = launcher.stop_all()
    assert codes == {"controller": 0, "sim": 0, "recorder": 0}, codes
    bag = open_bag(bag_dir)
    played = bag.joint_trajectory("/crane/reference", ["slew", "luff", "hoist"])
    # the published reference is the bag's trajectory at the controller's clock since its start
    tt = played.t - played.t[0]
    want = read_reference(ref, "/crane/reference", ["slew", "luff", "hoist"])(tt)[0]
    np.testing.assert_allclose(played.positions, want, atol=1e-6)
    # and the crane follows it (PD + feedforward, after the first second's pull to the start)
    js = bag.joint_state("/crane/joint_states", ["slew", "luff", "hoist"])
    late = tt > 2.0
    q = np.stack([np.interp(played.t[late], js.t, js.position[:, j]) for j in range(3)], axis=1)
    assert np.max(np.abs(q - played.positions[late]), axis=0)[0] < 0.1
    assert np.ptp(played.positions[:, 1]) > 0.1            # the designed motion moves the luff
