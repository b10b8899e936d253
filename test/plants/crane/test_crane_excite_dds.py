"""The crane controller plays a designed reference (``reference_bag``) over DDS: what it
publishes on /crane/reference is the bag's trajectory, and the simulated crane follows it."""
from __future__ import annotations

from pathlib import Path

import numpy as np

import cablelab.plants.crane as crane_pkg


def test_controller_plays_the_reference_bag(play_designed):
    desc_text = (Path(crane_pkg.__file__).parent / "data" / "crane.yaml").read_text()
    bag, played, want, _ = play_designed(
        "crane", desc_text, ["OF[luff]", "m_c"],
        [("sim", "cable_sim_node", {"rate": 100.0, "wait_for_subscribers": 2})],
        {"/crane/joint_states": 800, "/crane/reference": 600, "/plant_description": 1},
        ["slew", "luff", "hoist"])
    # the published reference is the bag's trajectory at the controller's clock since its start
    np.testing.assert_allclose(played.positions, want, atol=1e-6)
    tt = played.t - played.t[0]
    # and the crane follows it (PD + feedforward, after the first second's pull to the start)
    js = bag.joint_state("/crane/joint_states", ["slew", "luff", "hoist"])
    late = tt > 2.0
    q = np.stack([np.interp(played.t[late], js.t, js.position[:, j]) for j in range(3)], axis=1)
    assert np.max(np.abs(q - played.positions[late]), axis=0)[0] < 0.1
    assert np.ptp(played.positions[:, 1]) > 0.1            # the designed motion moves the luff
