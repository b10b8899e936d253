"""A pose-sensor offset is reported in metres (spec 000 sec. 7: +-0.05 m), not as the torque the
swing equation fits: a mocap position offset of (+20, -10) mm added to a simulated free swing
comes back as d_rx, d_ry within 10 % (the fitted torques stay under "internal")."""
import dataclasses

import numpy as np
import pytest

from cablelab.plants.suspended.bag import description_yaml, write_run
from cablelab.plants.suspended.mjcf import build_virtual
from cablelab.plants.suspended.params import parameter_set
from cablelab.plants.suspended.sim import initial_state, simulate
from cablelab.workbench import build_model, identify_report, load

OFFSET = np.array([0.02, -0.01, 0.0])          # m, added to every measured platform position


def test_pose_offset_in_metres(tmp_path):
    p = parameter_set("licas")
    m = build_virtual(p)
    r = simulate(m, initial_state(m, {"J8": 0.15, "J9": 0.12, "J11": -0.15}), 12.0)[0]
    write_run(tmp_path / "off", dataclasses.replace(r, pos=r.pos + OFFSET), p.S,
              description_yaml("licas"), pos_noise=1e-3, seed=7)
    plant, desc, ds = load(tmp_path / "off")
    out = identify_report(ds, build_model(plant, desc, ["pose_sensor_offset"]), folds=0)
    assert out.params["d_rx"]["unit"] == "m"
    assert out.params["d_rx"]["value"] == pytest.approx(OFFSET[0], rel=0.1)
    assert out.params["d_ry"]["value"] == pytest.approx(OFFSET[1], rel=0.1)
    assert 0 < out.params["d_rx"]["stderr"] < 0.1 * abs(OFFSET[0])
    assert {"off_x", "off_y", "off_yaw"} <= set(out.internal)
    assert "d_yaw" not in out.params          # no yaw stiffness in the model: no angle to give
