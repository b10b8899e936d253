"""Crane nodes: adapters fed bad input (in process) and sim + estimator + controller + recorder
over DDS, checked against the simulator's ground truth and the control law."""
from __future__ import annotations

import sys

import numpy as np
import pytest

from cablelab.ros.inputs import WARN


def test_adapters_survive_nan_wrong_length_stale(ros_context):
    from sensor_msgs.msg import JointState
    from std_msgs.msg import Float64MultiArray

    from cablelab.ros import convert
    from cablelab.plants.crane.nodes.sim import CraneSimNode
    from cablelab.plants.crane.nodes.estimator import CraneSwingEstimator
    from cablelab.plants.crane.nodes.controller import CraneController

    sim, est, ctl = CraneSimNode(), CraneSwingEstimator(), CraneController()
    sent, swings = [], []
    ctl.pub_cmd.publish = sent.append
    est.pub.publish = swings.append
    try:
        # simulator: bad commands rejected, stale command -> hold (the crane does not fall)
        for bad in ([float("nan"), 0, 0], [1.0, 2.0], []):
            sim.on_command(Float64MultiArray(data=bad))
        assert sim.u is None and sim.inputs.inputs["effort_commands"].rejected == 3
        for _ in range(50):
            sim.tick()
        _, q, _ = sim.sim.state()
        assert abs(q[1] - 0.5) < 1e-3 and sim.sim.held == 50
        # estimator: NaN pose = dropout, reported; good pair -> exact swing
        m = sim.sim.measurement()
        t = sim.sim.time
        est.on_tip(convert.pose_msg(t, m["tip"], m["tip_quat"]))
        est.on_payload(convert.pose_msg(t, m["payload"], m["payload_quat"]))
        assert not swings                       # waits for the slew angle of that stamp
        est.on_joints(convert.joint_state_msg(t, ["slew", "luff", "hoist"], m["joints"]))
        assert len(swings) == 1 and swings[0].position[2] == pytest.approx(0.6, abs=1e-9)
        est.on_tip(convert.pose_msg(t + 0.01, [np.nan] * 3, m["tip_quat"]))
        est.on_payload(convert.pose_msg(t + 0.01, [np.nan] * 3, m["payload_quat"]))
        est.on_joints(convert.joint_state_msg(t + 0.01, ["slew", "luff", "hoist"], m["joints"]))
        est.on_payload(convert.pose_msg(t, m["payload"], m["payload_quat"]))   # unpaired stamp
        est.on_joints(JointState())
        level, msg, values = est.status()
        assert level >= WARN and "dropout" in msg and len(swings) == 1
        # controller: waits for the description, rejects bad states, falls back without reference
        js = convert.joint_state_msg(t, ["slew", "luff", "hoist"], m["joints"], m["joint_rates"], m["effort"])
        ctl.on_state(js)
        assert not sent
        ctl.on_description(convert.string_msg(sim.description.to_yaml()))
        ctl.on_state(js)
        assert len(sent) == 1 and ctl.fallbacks == 1   # no reference: hold = gravity compensation
        np.testing.assert_allclose(sent[0].data, m["effort"], atol=1e-6)
        ctl.on_state(convert.joint_state_msg(t, ["slew", "luff", "hoist"], [np.nan, 0, 0]))
        ctl.on_state(convert.joint_state_msg(t, ["slew", "luff"], [0, 0]))
        assert len(sent) == 1 and ctl.inputs.inputs["joint_states"].rejected == 2
        ctl.reference.on_message(convert.joint_trajectory_msg(t, ["slew", "luff", "hoist"], m["joints"] + [0.1, 0, 0],
                                                      [0, 0, 0], [0, 0, 0]))
        ctl.on_state(js)
        assert sent[-1].data[0] == pytest.approx(ctl.gains.kp[0] * 0.1, rel=1e-6)
    finally:
        for n in (sim, est, ctl):
            n.destroy_node()


def test_crane_nodes_over_dds(launcher, tmp_path):
    from cablelab.bags import open_bag
    from cablelab.plants.crane import estimate as C

    bag_dir = tmp_path / "run"
    launcher.start("recorder", [sys.executable, "-m", "cablelab.cli", "record", "--plant", "crane",
                                "-o", bag_dir, "--quiet"])
    # a recorder still importing on a busy machine would miss the start: wait for its subscriptions
    launcher.wait_for_subscribers(["/crane/joint_states", "/crane/effort_commands",
                                   "/crane/swing_estimate"], timeout=120, node_name="cablelab_recorder")
    # (time starts once the recorder, the estimator and the controller are matched on the states)
    launcher.node("sim", "cable_sim_node", "crane", {"rate": 100.0, "mocap_dropout": 0.02,
                                                     "wait_for_subscribers": 3})
    launcher.node("estimator", "payload_estimator", "crane", {})
    launcher.node("controller", "pd_feedforward", "crane", {"reference_source": "excitation"})
    # what the checks below read is the bag: wait until it holds the run (8 s of motion)
    launcher.wait_for_recorded(bag_dir, {"/crane/joint_states": 800, "/crane/effort_commands": 600,
                                         "/crane/swing_estimate": 600, "/crane/reference": 600,
                                         "/plant_description": 1}, timeout=180)
    codes = launcher.stop_all()
    assert codes == {"estimator": 0, "controller": 0, "sim": 0, "recorder": 0}, codes

    bag = open_bag(bag_dir)
    assert bag.description.plant == "crane"
    est = bag.joint_state("/crane/swing_estimate", ["theta1", "theta2", "rope_length"])
    tru = bag.joint_state("/crane/ground_truth/swing", ["theta1", "theta2", "rope_length"])
    idx = np.searchsorted(tru.t, est.t)
    ok = (idx < tru.t.size) & (np.abs(tru.t[np.clip(idx, 0, tru.t.size - 1)] - est.t) < 1e-9)
    assert ok.mean() > 0.95
    # live swing angles and rope length = simulation truth (exact inverse, no noise)
    diff = est.position[ok] - tru.position[idx[ok]]
    diff[:, :2] = np.angle(np.exp(1j * diff[:, :2]))   # the live estimate unwraps theta1
    np.testing.assert_allclose(diff, 0.0, atol=1e-9)
    # live rates are first differences smoothed by a first-order low-pass (tau = 20 ms):
    # (1) a second implementation of that recursion over the published angles gives them exactly;
    # (2) they follow the true swing rates passed through the same low-pass (so the filter's lag,
    #     largest at the excitation's start-up, is not counted as an estimation error)
    vt, ve, te = tru.velocity[idx[ok]], est.velocity[ok], est.t[ok]
    # (the recording may start after the tracker did: the re-implementation starts from rest, and
    # its start-up difference decays as (1 - a)^k, a = dt / (tau + dt) = 1/3 at 100 Hz, so it is
    # compared from the 60th recorded sample on, where (2/3)^60 < 1e-10)
    v_rec = _lowpassed_differences(est.t, est.position, tau=0.02)[ok]
    settled = np.arange(len(est.t))[ok] >= 60
    np.testing.assert_allclose(ve[settled], v_rec[settled], atol=1e-6)
    vt_f = _lowpass(te, vt, tau=0.02)
    late = te > te[0] + 1.0
    for j in range(3):
        rms_true = np.sqrt(np.mean(vt[late, j] ** 2))
        assert np.sqrt(np.mean((ve[late, j] - vt_f[late, j]) ** 2)) < 0.15 * rms_true + 1e-3, j
    # the crane moved and the swing is non-trivial
    js = bag.joint_state("/crane/joint_states", ["slew", "luff", "hoist"])
    assert np.ptp(js.position[:, 0]) > 0.05
    # lock-step, no control delay however slow the machine: once commands flow, the effort applied
    # over each period (reported with the state that ends it, exactly: no effort noise, no
    # offset) is the controller's answer to the state that starts it. The controller answers
    # every state in order, so the recorded commands and the applied efforts are one sequence
    # shifted by one period (answers to states of the real-time start, before the first
    # command arrived, are ignored by the simulator)
    cmd = bag.float_array("/crane/effort_commands").data
    eff = js.effort
    mid = len(cmd) // 2
    hit = np.flatnonzero(np.all(eff == cmd[mid], axis=1))
    assert len(hit) == 1, hit
    shift = hit[0] - mid                       # eff[k + shift] = cmd[k]
    k = np.arange(max(0, -shift), min(len(cmd), len(eff) - shift))
    same = np.all(eff[k + shift] == cmd[k], axis=1)
    assert same[len(k) // 10:].all(), np.flatnonzero(~same)
    # it tracks the reference it was given
    ref = bag.joint_trajectory("/crane/reference", ["slew", "luff", "hoist"])
    late = ref.t > ref.t[0] + 2.0
    q_at = np.column_stack([np.interp(ref.t[late], js.t, js.position[:, j]) for j in range(3)])
    assert np.abs(q_at - ref.positions[late]).max() < 0.05
    # offline estimate of the same bag (cablelab estimate path) reports the dropouts
    out = C.estimate_bag(bag)
    assert out["conditioning"]["dropouts"] > 0 and out["samples"] > 500
    assert out["rms_error_vs_ground_truth"]["theta1"] < 1e-3


def _lowpass(t, u, tau):
    """First-order low-pass y_k = y_{k-1} + dt/(tau+dt) (u_k - y_{k-1}), y_0 = u_0 (test oracle)."""
    y = np.empty_like(u)
    y[0] = u[0]
    for k in range(1, len(t)):
        a = (t[k] - t[k - 1]) / (tau + t[k] - t[k - 1])
        y[k] = y[k - 1] + a * (u[k] - y[k - 1])
    return y


def _lowpassed_differences(t, x, tau, stale_after=0.5):
    """The live tracker's rate, re-implemented: low-passed first differences, restarting at 0
    after a gap longer than ``stale_after`` (test oracle for SwingTracker)."""
    v = np.zeros_like(x)
    for k in range(1, len(t)):
        dt = t[k] - t[k - 1]
        if dt > stale_after:
            continue
        v[k] = v[k - 1] + dt / (tau + dt) * ((x[k] - x[k - 1]) / dt - v[k - 1])
    return v
