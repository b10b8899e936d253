"""The mjcf controller plays a designed reference (``reference_bag``, written as ``cablelab
excite --plant mjcf`` writes it) over DDS: what it publishes on /mjcf/reference is the bag's
trajectory, and the simulated arm follows it."""
from __future__ import annotations

import sys

import numpy as np
import yaml

from cablelab.bags import open_bag
from cablelab.description import load_description
from cablelab.excite import design, get_exciter, read_reference, write_reference
from cablelab.plants.mjcf.examples import ARM3

JOINTS = ["base_yaw", "shoulder", "elbow"]


def test_mjcf_controller_plays_the_reference_bag(launcher, tmp_path):
    desc_file = tmp_path / "arm.yaml"
    desc_file.write_text(yaml.safe_dump({"plant": "mjcf", "mjcf": {"model_file": str(ARM3),
                                                                    "payload_body": "tool"}}))
    desc = load_description(str(desc_file))
    d = design("mjcf", desc, ["m", "OF[shoulder]"], duration=12.0, max_iter=5)
    ref = tmp_path / "ref"
    write_reference(ref, d, get_exciter("mjcf"))
    bag_dir = tmp_path / "run"
    launcher.start("recorder", [sys.executable, "-m", "cablelab.cli", "record", "--plant", "mjcf",
                                "-o", bag_dir, "--quiet"])
    launcher.wait_for_subscribers(["/mjcf/joint_states", "/mjcf/reference"], timeout=120,
                                  node_name="cablelab_recorder")
    launcher.node("controller", "pd_feedforward", "mjcf", {"reference_bag": str(ref)})
    launcher.node("sim", "cable_sim_node", "mjcf", {"description": str(desc_file), "rate": 200.0,
                                                    "wait_for_subscribers": 2})
    launcher.wait_for_recorded(bag_dir, {"/mjcf/joint_states": 1000, "/mjcf/reference": 900},
                               timeout=240)
    codes = launcher.stop_all()
    assert codes == {"recorder": 0, "controller": 0, "sim": 0}, codes
    bag = open_bag(bag_dir)
    played = bag.joint_trajectory("/mjcf/reference", JOINTS)
    # the published reference is the bag's trajectory at the controller's clock since its start
    tt = played.t - played.t[0]
    want = read_reference(ref, "/mjcf/reference", JOINTS)(tt)
    np.testing.assert_allclose(played.positions, want[0], atol=1e-9)
    np.testing.assert_allclose(played.velocities, want[1], atol=1e-9)
    # and the arm follows it (computed torque with the model: within a tenth of each joint's
    # designed stroke after the first second)
    js = bag.joint_state("/mjcf/joint_states", JOINTS)
    t, first = np.unique(js.t, return_index=True)
    late = tt > 1.0
    stroke = np.ptp(played.positions, axis=0)
    assert stroke.min() > 0.1                                 # it was asked to move
    for k in range(3):
        q = np.interp(played.t[late], t, js.position[first, k])
        assert np.max(np.abs(q - played.positions[late, k])) < 0.1 * stroke[k], JOINTS[k]
