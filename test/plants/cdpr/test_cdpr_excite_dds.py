"""The CDPR's experiment-design loop over DDS: hidden dynamometer offsets that the lift at the
pick point confounds with the payload's mass and centre of mass, a designed reference played by
``pd_feedforward --plant cdpr -p reference_bag:=REF`` to ``cable_sim_node --plant cdpr`` (which
hides the same offsets, ``tension_bias``) with the payload estimator and the recorder, and the fit
on that recording: separated, and the offsets, mass and centre of mass come back.

Oracle: the simulator's hidden truth (offsets, payload) and its ground-truth pose."""
from __future__ import annotations

import numpy as np
import pytest

from cablelab.plants.cdpr import demo
from cablelab.plants.cdpr.excite import start_position
from cablelab.plants.cdpr.sim import default_description, default_description_path, simulate, write_run_bag

DESIGNED_S = 30.0


def _offset_errors(fit) -> np.ndarray:
    return np.array([fit.params[p] - b for p, b in zip(demo.LOOP_PARAMS, demo.LOOP_BIAS)])


def test_designed_reference_over_dds_separates_offsets_from_payload(play_designed, tmp_path):
    truth = demo.loop_truth().resolved(default_description())
    # the lift at the pick point: the diagnosis finds the offsets confounded with the payload
    lift = tmp_path / "lift"
    write_run_bag(simulate(default_description(), demo.loop_truth(), duration=demo.LOOP_LIFT_S), lift)
    _, f0, conf0, c0 = demo.loop_fit(lift)
    assert c0 > 1e6
    assert {r["with"] for r in conf0 if abs(r["correlation"]) >= 0.9} & {"m", "mx", "my"}
    assert max(f0.stderr[p] for p in demo.LOOP_PARAMS[:8]) > 30.0       # offsets not determined

    bag, played, want, _ = play_designed(
        "cdpr", open(default_description_path()).read(), list(demo.LOOP_PARAMS),
        [("sim", "cable_sim_node", {**demo.loop_sim_params(), "real_time": False, "publish_reference": False,
                                    "wait_for_subscribers": 2, **demo.LOCKSTEP_PATIENCE["sim"]}),
         ("estimator", "payload_estimator", {"model": "II", "tensions": "dynamometer"})],
        {"/cdpr/joint_states": int(DESIGNED_S * 100), "/cdpr/reference": int(DESIGNED_S * 100) - 50,
         "/cdpr/cable_tensions": int(DESIGNED_S * 100)},
        ["x", "y", "z"], duration=DESIGNED_S, max_iter=10, timeout=400,
        controller=demo.LOCKSTEP_PATIENCE["controller"])
    # the controller published the bag's trajectory, from the simulator's start pose on: the
    # platform (ground truth) is where the reference starts and follows it without a jump
    np.testing.assert_allclose(played.positions, want, atol=1e-6)
    np.testing.assert_allclose(played.positions[0], start_position(), atol=1e-9)
    gt = bag.pose("/cdpr/ground_truth/pose")
    true_at = np.stack([np.interp(played.t, gt.t, gt.position[:, j]) for j in range(3)], axis=1)
    assert np.linalg.norm(true_at[0] - start_position()) < 0.01
    assert np.max(np.linalg.norm(true_at - played.positions, axis=1)) < 0.03
    assert np.ptp(played.positions, axis=0).min() > 0.3               # it moved the platform
    # every cable taut in every sample (the dynamometers less their hidden offsets): no state
    # stepped on the winch brakes
    tensions = bag.joint_state("/cdpr/cable_tensions", [f"cable_{i}" for i in range(1, 9)]).effort
    assert np.min(tensions - np.array(demo.LOOP_BIAS)) > 100.0
    # the fit on the designed recording: nothing confounded, the offsets and payload come back
    _, f1, conf1, c1 = demo.loop_fit(bag.path)
    assert conf1 == [] and c1 < 3e3 and c1 < c0 / 1e3
    assert np.abs(_offset_errors(f1)).max() < 15.0, _offset_errors(f1)
    assert f1.params["m"] == pytest.approx(truth.total_mass, rel=0.01)
    for k, c in (("mx", truth.total_com[0]), ("my", truth.total_com[1])):
        assert f1.params[k] == pytest.approx(truth.total_mass * c, abs=2.5)     # 5 mm of CoM
    # while the lift left at least one offset further off than the designed run's worst
    assert np.abs(_offset_errors(f0)).max() > np.abs(_offset_errors(f1)).max()
