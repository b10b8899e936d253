"""``cable_sim_node --plant mjcf`` over DDS: the recorded run is the description's own model
stepped at its timestep (oracle: the same model stepped offline, a separate process), the bag
carries the model inline and the workbench reads it."""
from __future__ import annotations

import sys

import numpy as np
import yaml

from cablelab.bags import open_bag
from cablelab.description import load_description
from cablelab.plants.mjcf.examples import ARM3, CABLECAM
from cablelab.plants.mjcf.sim import MjcfSim


def test_sim_node_publishes_the_models_motion(launcher, tmp_path):
    desc = tmp_path / "arm.yaml"
    desc.write_text(yaml.safe_dump({"plant": "mjcf", "mjcf": {"model_file": str(ARM3),
                                                               "payload_body": "tool"}}))
    bag_dir = tmp_path / "run"
    launcher.start("recorder", [sys.executable, "-m", "cablelab.cli", "record", "--plant", "mjcf",
                                "-o", bag_dir, "--quiet"])
    launcher.wait_for_subscribers(["/mjcf/joint_states"], timeout=120, node_name="cablelab_recorder")
    launcher.node("sim", "cable_sim_node", "mjcf", {"description": str(desc), "rate": 100.0,
                                                    "wait_for_subscribers": 1})
    launcher.wait_for_recorded(bag_dir, {"/mjcf/joint_states": 150, "/plant_description": 1},
                               timeout=180)
    codes = launcher.stop_all()
    assert codes["sim"] == 0 and codes["recorder"] == 0, codes

    bag = open_bag(bag_dir)
    assert bag.description.plant == "mjcf" and bag.description.mjcf.model == ARM3.read_text()
    js = bag.joint_state("/mjcf/joint_states")
    assert js.names == ["base_yaw", "shoulder", "elbow"]
    t, first = np.unique(js.t, return_index=True)
    steps = np.round(t / 0.01).astype(int)
    np.testing.assert_allclose(t, steps * 0.01, atol=1e-9)       # whole periods of sim time
    # the same model stepped offline with zero controls (no controller: a falling arm)
    sim = MjcfSim(load_description(str(desc)).mjcf)
    q_off = {}
    for k in range(steps.max() + 1):
        q_off[k] = sim.state()[1]
        sim.advance([0.0, 0.0, 0.0], 0.01)
    expect = np.array([q_off[k] for k in steps])
    np.testing.assert_allclose(js.position[first], expect, atol=1e-9)
    assert np.ptp(js.position[first, 1]) > 0.5                   # it did move (gravity)
    np.testing.assert_allclose(js.effort[first], 0.0, atol=1e-12)


def test_payload_estimator_finds_the_simulated_payload(launcher, tmp_path):
    """Simulator with a 1.2 kg payload the description does not have (a passively swinging arm),
    the estimator node fitting the live joint states: its last estimates within 5 %."""
    desc = tmp_path / "arm.yaml"
    desc.write_text(yaml.safe_dump({"plant": "mjcf", "mjcf": {"model_file": str(ARM3),
                                                               "payload_body": "tool"}}))
    bag_dir = tmp_path / "run"
    launcher.start("recorder", [sys.executable, "-m", "cablelab.cli", "record", "--plant", "mjcf",
                                "-o", bag_dir, "--quiet"])
    launcher.wait_for_subscribers(["/mjcf/joint_states"], timeout=120, node_name="cablelab_recorder")
    launcher.node("estimator", "payload_estimator", "mjcf", {"window": 2.0, "publish_every": 100})
    launcher.node("sim", "cable_sim_node", "mjcf", {"description": str(desc), "rate": 500.0,
                                                    "payload_mass": 1.2, "wait_for_subscribers": 2})
    launcher.wait_for_recorded(bag_dir, {"/mjcf/payload_estimate": 8}, timeout=240)
    codes = launcher.stop_all()
    assert codes == {"recorder": 0, "estimator": 0, "sim": 0}, codes
    est = open_bag(bag_dir).inertia("/mjcf/payload_estimate")
    np.testing.assert_allclose(est.m[-3:], 1.2, rtol=0.05)


def test_pd_feedforward_tracks_with_the_models_inverse_dynamics(launcher, tmp_path):
    """Simulator, computed-torque controller (built-in sine) and recorder as processes: with the
    same model in the feedforward the arm follows the published reference (RMS < 0.02 rad after
    the first second)."""

    desc = tmp_path / "arm.yaml"
    desc.write_text(yaml.safe_dump({"plant": "mjcf", "mjcf": {"model_file": str(ARM3)}}))
    bag_dir = tmp_path / "run"
    launcher.start("recorder", [sys.executable, "-m", "cablelab.cli", "record", "--plant", "mjcf",
                                "-o", bag_dir, "--quiet"])
    launcher.wait_for_subscribers(["/mjcf/joint_states"], timeout=120, node_name="cablelab_recorder")
    launcher.node("controller", "pd_feedforward", "mjcf",
                  {"reference_source": "sine", "amplitude": 0.3, "frequency": 0.5})
    launcher.node("sim", "cable_sim_node", "mjcf", {"description": str(desc), "rate": 200.0,
                                                    "wait_for_subscribers": 2})
    launcher.wait_for_recorded(bag_dir, {"/mjcf/joint_states": 600, "/mjcf/reference": 400}, timeout=240)
    codes = launcher.stop_all()
    assert codes == {"recorder": 0, "controller": 0, "sim": 0}, codes
    bag = open_bag(bag_dir)
    js = bag.joint_state("/mjcf/joint_states")
    ref = bag.joint_trajectory("/mjcf/reference")
    t_ref, k = np.unique(ref.t, return_index=True)
    q_ref = ref.positions[k]
    t, first = np.unique(js.t, return_index=True)
    q = js.position[first]
    late = t_ref > t_ref[0] + 1.0
    q_at = np.column_stack([np.interp(t_ref[late], t, q[:, j]) for j in range(3)])
    err = np.abs(q_at - q_ref[late])
    assert np.sqrt(np.mean(err**2)) < 0.02, np.sqrt(np.mean(err**2, axis=0))
    assert np.ptp(q_ref[late], axis=0).min() > 0.3          # it did move (amplitude 0.3 rad)


def test_payload_estimator_weighs_the_camera_from_its_cable_tensions(launcher, tmp_path):
    """The four-cable camera robot carrying 1.5 kg its description lacks, moved by the
    computed-torque controller (built-in sine), the estimator fitting the live joint states and
    the measured cable tensions (no joint effort is measured on this machine): its last
    estimates within 5 % of the simulated camera mass."""
    desc = tmp_path / "cam.yaml"
    desc.write_text(yaml.safe_dump({"plant": "mjcf", "mjcf": {
        "model_file": str(CABLECAM), "payload_body": "carriage",
        "tendons": ["cable_1", "cable_2", "cable_3", "cable_4"]}}))
    bag_dir = tmp_path / "run"
    launcher.start("recorder", [sys.executable, "-m", "cablelab.cli", "record", "--plant", "mjcf",
                                "-o", bag_dir, "--quiet"])
    launcher.wait_for_subscribers(["/mjcf/joint_states"], timeout=120, node_name="cablelab_recorder")
    launcher.node("estimator", "payload_estimator", "mjcf", {"window": 3.0, "publish_every": 100})
    launcher.node("controller", "pd_feedforward", "mjcf",
                  {"reference_source": "sine", "amplitude": 0.3, "frequency": 0.5})
    launcher.node("sim", "cable_sim_node", "mjcf", {"description": str(desc), "rate": 200.0,
                                                    "payload_mass": 1.5, "wait_for_subscribers": 3})
    launcher.wait_for_recorded(bag_dir, {"/mjcf/payload_estimate": 8}, timeout=300)
    codes = launcher.stop_all()
    assert codes == {"recorder": 0, "estimator": 0, "controller": 0, "sim": 0}, codes
    bag = open_bag(bag_dir)
    ten = bag.joint_state("/mjcf/cable_tensions")
    assert ten.names == ["cable_1", "cable_2", "cable_3", "cable_4"] 
    assert np.all(ten.effort[ten.t > 1.0] > 0)                  # the cables pull (controlled)
    est = bag.inertia("/mjcf/payload_estimate")
    np.testing.assert_allclose(est.m[-3:], 1.5, rtol=0.05)
