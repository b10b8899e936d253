"""The leg controller plays a designed apex-height schedule (``reference_bag``) over DDS: what it
publishes on /leg/reference is the bag's schedule at its clock, and the leg hops under it."""
from __future__ import annotations

import sys
from pathlib import Path

import numpy as np

import cablelab.plants.leg as leg_pkg
from cablelab.description import load_description
from cablelab.excite import design, get_exciter, read_reference, write_reference


def test_leg_controller_plays_the_reference_bag(launcher, tmp_path):
    from cablelab.bags import open_bag

    desc_text = (Path(leg_pkg.__file__).parent / "data" / "leg.yaml").read_text()
    desc = load_description(desc_text)
    d = design("leg", desc, ["F0", "m"], duration=12.0, max_iter=3)
    ref = tmp_path / "ref"
    write_reference(ref, d, get_exciter("leg"), desc_text)
    bag_dir = tmp_path / "run"
    launcher.start("recorder", [sys.executable, "-m", "cablelab.cli", "record", "--plant", "leg",
                                "-o", bag_dir, "--quiet"])
    launcher.wait_for_subscribers(["/leg/joint_states", "/leg/reference"], timeout=120,
                                  node_name="cablelab_recorder")
    launcher.node("sim", "cable_sim_node", "leg", {})
    launcher.node("estimator", "payload_estimator", "leg", {})
    launcher.node("controller", "pd_feedforward", "leg", {"reference_bag": str(ref)})
    launcher.wait_for_recorded(bag_dir, {"/leg/joint_states": 2000, "/leg/reference": 500,
                                         "/plant_description": 1}, timeout=240)
    codes = launcher.stop_all()
    assert codes == {"controller": 0, "estimator": 0, "sim": 0, "recorder": 0}, codes
    bag = open_bag(bag_dir)
    played = bag.joint_trajectory("/leg/reference", ["apex_height"])
    tt = played.t - played.t[0]
    want = read_reference(ref, "/leg/reference", ["apex_height"])(tt)[0]
    np.testing.assert_allclose(played.positions, want, atol=1e-9)
    lim = get_exciter("leg").limits(desc)
    assert np.all(played.positions >= lim.lower[0]) and np.all(played.positions <= lim.upper[0])
    # and the leg hops under it: the contact switch opens and closes
    contact = bag.joint_state("/leg/contact", ["contact"]).position[:, 0]
    assert np.count_nonzero(np.diff(contact > 0.5)) >= 4
