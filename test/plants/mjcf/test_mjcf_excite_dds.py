"""The mjcf controller plays a designed reference (``reference_bag``, written as ``cablelab
excite --plant mjcf`` writes it) over DDS: what it publishes on /mjcf/reference is the bag's
trajectory, and the simulated arm follows it."""
from __future__ import annotations

import numpy as np
import yaml

from cablelab.plants.mjcf.examples import ARM3

JOINTS = ["base_yaw", "shoulder", "elbow"]


def test_mjcf_controller_plays_the_reference_bag(play_designed, tmp_path):
    text = yaml.safe_dump({"plant": "mjcf", "mjcf": {"model_file": str(ARM3), "payload_body": "tool"}})
    desc_file = tmp_path / "arm.yaml"
    desc_file.write_text(text)
    bag, played, want, _desc = play_designed(
        "mjcf", text, ["m", "OF[shoulder]"],
        [("sim", "cable_sim_node", {"description": str(desc_file), "rate": 200.0, "wait_for_subscribers": 2})],
        {"/mjcf/joint_states": 1000, "/mjcf/reference": 900}, JOINTS, timeout=240)
    # the published reference is the bag's trajectory at the controller's clock since its start
    np.testing.assert_allclose(played.positions, want, atol=1e-9)
    # and the arm follows it (computed torque with the model: within a tenth of each joint's
    # designed stroke after the first second)
    js = bag.joint_state("/mjcf/joint_states", JOINTS)
    t, first = np.unique(js.t, return_index=True)
    late = played.t - played.t[0] > 1.0
    stroke = np.ptp(played.positions, axis=0)
    assert stroke.min() > 0.1                                 # it was asked to move
    for k in range(3):
        q = np.interp(played.t[late], t, js.position[first, k])
        assert np.max(np.abs(q - played.positions[late, k])) < 0.1 * stroke[k], JOINTS[k]
