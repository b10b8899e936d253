"""The axis controller plays a designed reference (``reference_bag``) over DDS: what it publishes
on /axis/reference is the bag's trajectory, and the simulated axis follows it."""
from __future__ import annotations

import numpy as np

from cablelab.plants.axis.sim import DEFAULT_DESCRIPTION


def test_axis_controller_plays_the_reference_bag(play_designed):
    bag, played, want, _ = play_designed(
        "axis", DEFAULT_DESCRIPTION, ["Fc", "OF"],
        [("sim", "cable_sim_node", {"rate": 200.0, "lockstep": True, "wait_for_subscribers": 2})],
        {"/axis/joint_states": 1000, "/axis/reference": 900, "/plant_description": 1}, ["joint"])
    # the published reference is the bag's trajectory at the controller's clock since its start
    np.testing.assert_allclose(played.positions, want, atol=1e-6)
    tt = played.t - played.t[0]
    # and the axis follows it (PD + feedforward: within a tenth of the designed stroke after 1 s)
    js = bag.joint_state("/axis/joint_states", ["joint"])
    late = tt > 1.0
    q = np.interp(played.t[late], js.t, js.position[:, 0])
    stroke = np.ptp(played.positions[:, 0])
    assert stroke > 0.05
    assert np.max(np.abs(q - played.positions[late, 0])) < 0.1 * stroke
