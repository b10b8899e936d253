"""The leg controller plays a designed apex-height schedule (``reference_bag``) over DDS: what it
publishes on /leg/reference is the bag's schedule at its clock, and the leg hops under it. The
simulator runs in lock-step (time starts with the controller's answer to the start state): in
real time it steps on without torque while the estimator and the controller are still starting,
and on a loaded machine the samples the test records held as few as three switch edges (also in
lock-step once, under a full test run's load: 3000 samples, not 2000, leave room for two hops)."""
from __future__ import annotations

from pathlib import Path

import numpy as np

import cablelab.plants.leg as leg_pkg
from cablelab.excite import get_exciter


def test_leg_controller_plays_the_reference_bag(play_designed):
    desc_text = (Path(leg_pkg.__file__).parent / "data" / "leg.yaml").read_text()
    bag, played, want, desc = play_designed(
        "leg", desc_text, ["F0", "m"],
        [("sim", "cable_sim_node", {"lockstep": True}), ("estimator", "payload_estimator", {})],
        {"/leg/joint_states": 3000, "/leg/reference": 500, "/plant_description": 1}, ["apex_height"],
        max_iter=3, timeout=240)
    np.testing.assert_allclose(played.positions, want, atol=1e-9)
    lim = get_exciter("leg").limits(desc)
    assert np.all(played.positions >= lim.lower[0]) and np.all(played.positions <= lim.upper[0])
    # and the leg hops under it: the contact switch opens and closes
    contact = bag.joint_state("/leg/contact", ["contact"]).position[:, 0]
    assert np.count_nonzero(np.diff(contact > 0.5)) >= 4
