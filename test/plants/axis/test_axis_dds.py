"""Multi-process integration over DDS: axis simulator, controller, estimator and the recorder run
as separate processes on a unique ROS_DOMAIN_ID; the recorded bag must be physically consistent.

Oracles: finite differences of the recorded positions vs the recorded velocities (the simulator's
integration), the controller law recomputed from recorded inputs, the true simulator parameters
vs the live estimate, and the reference vs the response."""
from __future__ import annotations

import sys

import numpy as np

from cablelab.bags import open_bag
from cablelab.plants.axis.control import pd_feedforward, sine_reference

AMPLITUDE, FREQUENCY, KP, KD = 0.2, 1.0, 400.0, 40.0
TRUE = {"inertia": 2.0, "viscous": 5.0, "coulomb": 1.0}


def test_sim_controller_estimator_recorder_over_dds(launcher, tmp_path):
    bag_dir = tmp_path / "run"
    launcher.start("recorder", [sys.executable, "-m", "cablelab.cli", "record", "--plant", "axis",
                                "-o", bag_dir, "--quiet"])
    # a recorder still importing on a busy machine would miss the start: wait for its subscriptions
    launcher.wait_for_subscribers(["/axis/joint_states", "/axis/effort_command", "/axis/reference"],
                                  timeout=120, node_name="cablelab_recorder")
    # lock-step: the plant waits for the answer to each state, so a loaded machine slows the run
    # down but cannot add control delay (the physics checks below are then deterministic)
    # (time starts once the recorder, the controller and the estimator are matched on the states)
    launcher.node("sim", "cable_sim_node", "axis", {**TRUE, "rate": 200.0, "lockstep": True,
                                                    "wait_for_subscribers": 3})
    launcher.node("controller", "pd_feedforward", "axis",
                  {"reference_source": "sine", "amplitude": AMPLITUDE, "frequency": FREQUENCY,
                   "kp": KP, "kd": KD})
    launcher.node("estimator", "payload_estimator", "axis", {"publish_every": 10})
    # 4 s of simulated motion (800 samples) flowing through all four processes, in the bag
    launcher.wait_for_recorded(bag_dir, {"/axis/joint_states": 800, "/axis/effort_command": 600,
                                         "/axis/reference": 600, "/axis/parameter_estimate": 40,
                                         "/plant_description": 1}, timeout=180)
    codes = launcher.stop_all()
    assert codes == {"estimator": 0, "controller": 0, "sim": 0, "recorder": 0}, codes

    bag = open_bag(bag_dir)
    for topic in ("/clock", "/plant_description", "/axis/joint_states", "/axis/reference",
                  "/axis/effort_command", "/axis/parameter_estimate", "/axis/ground_truth/joint_states"):
        assert bag.counts.get(topic, 0) > 0, (topic, bag.counts)
    assert bag.description.plant == "axis" and bag.description.axis.inertia == 2.0

    js = bag.joint_state("/axis/joint_states")
    assert js.names == ["joint"]
    # (a state is resent while the sim waits for its first answer: keep one per stamp)
    _, first = np.unique(js.t, return_index=True)
    t, q, qd = js.t[first], js.position[first, 0], js.velocity[first, 0]
    # sim time advances by exactly one publishing period per message (no message lost on the way)
    np.testing.assert_allclose(np.diff(t), 1 / 200.0, atol=1e-9)
    # recorded velocity = derivative of recorded position (trapezoid rule of the integrator)
    dq = np.diff(q) / np.diff(t)
    np.testing.assert_allclose(dq, 0.5 * (qd[1:] + qd[:-1]), atol=0.02 * AMPLITUDE * 2 * np.pi * FREQUENCY)

    # lock-step, no control delay however slow the machine: the effort applied over each period
    # is the controller law of the state that starts it (law recomputed; a resent state answered
    # twice must not shift the commands by a period). The controller takes its feedforward
    # inertia from /plant_description: answers before that arrived use M_ff = 0, all later ones
    # M_ff = 2 (the switch comes early and once)
    ref_t = sine_reference(t, AMPLITUDE, FREQUENCY)
    applied = js.effort[first, 0][1:]

    def law_applied(inertia):
        u = pd_feedforward(q, qd, *ref_t, KP, KD, inertia=inertia)[:-1]
        return np.abs(applied - u) <= 1e-6 * (1.0 + np.abs(u))
    with_ff, without_ff = law_applied(2.0), law_applied(0.0)
    switch = len(with_ff) - np.argmin(with_ff[::-1]) if not with_ff.all() else 0
    assert without_ff[:switch].all() and with_ff[switch:].all(), np.flatnonzero(~(with_ff | without_ff))
    assert switch < 0.1 * len(applied), switch

    # the reference the controller published is the sine evaluated at the measurement stamps
    ref = bag.joint_trajectory("/axis/reference")
    q_ref, qd_ref, qdd_ref = sine_reference(ref.t, AMPLITUDE, FREQUENCY)
    np.testing.assert_allclose(ref.positions[:, 0], q_ref, atol=1e-12)
    np.testing.assert_allclose(ref.accelerations[:, 0], qdd_ref, atol=1e-9)

    # the axis follows its reference: after one period the error is a few % of the amplitude
    # (each topic's recording starts when DDS matched it: compare where both were recorded)
    late = (ref.t > max(ref.t[0], t[0]) + 1.0 / FREQUENCY) & (ref.t <= t[-1])
    assert late.sum() > 100
    q_at_ref = np.interp(ref.t[late], t, q)
    assert np.max(np.abs(q_at_ref - ref.positions[late, 0])) < 0.1 * AMPLITUDE
    assert np.ptp(q[t > t[0] + 1.0]) > 1.5 * AMPLITUDE  # it really moved

    # the commands are the PD + feedforward law of the recorded state (controller recomputed)
    cmd = bag.float_array("/axis/effort_command").data[:, 0]
    by_stamp = {round(s, 6): i for i, s in enumerate(t)}
    rows = [by_stamp.get(round(s, 6)) for s in ref.t]
    ok = np.array([r is not None for r in rows])
    idx = np.array([r for r in rows if r is not None])
    u = pd_feedforward(q[idx], qd[idx], q_ref[ok], qd_ref[ok], qdd_ref[ok], KP, KD, inertia=2.0)
    assert len(cmd) > 500 and ok.mean() > 0.95
    # every recorded command is the law applied to one recorded (state, reference) pair
    us = np.sort(u)
    pos = np.clip(np.searchsorted(us, cmd), 1, len(us) - 1)
    nearest = np.minimum(np.abs(us[pos] - cmd), np.abs(us[pos - 1] - cmd))
    # (the recorder may match the controller's command publisher before its reference publisher:
    # the very first commands can lack their recorded reference)
    bad = np.flatnonzero(nearest > 1e-6)
    assert len(bad) < 0.05 * len(cmd) and (bad < 0.05 * len(cmd)).all(), (bad, len(cmd))

    # ground truth effort is the command the simulator applied; it reports effort = command
    truth = bag.joint_state("/axis/ground_truth/joint_states")
    common, i_truth, i_js = np.intersect1d(np.round(truth.t, 6), np.round(js.t, 6), return_indices=True)
    # (the recorder may match the truth publisher a moment after the state publisher, e.g. 0.3 s
    # on a loaded machine: from its first sample on, none is missing)
    assert len(common) > 0.95 * np.count_nonzero(t >= truth.t[0]) and truth.t[0] < 0.5 * t[-1]
    np.testing.assert_array_equal(truth.effort[i_truth], js.effort[i_js])

    # live RLS estimate of [M, Fv, Fc, offset] converges to the simulated values (Coulomb friction
    # is a soft constraint in MuJoCo, so Fc is only loosely identified)
    est = bag.float_array("/axis/parameter_estimate").data[-1]
    assert abs(est[0] - TRUE["inertia"]) < 0.05 * TRUE["inertia"], est
    assert abs(est[1] - TRUE["viscous"]) < 0.2 * TRUE["viscous"], est
    assert 0.5 * TRUE["coulomb"] < est[2] < 1.5 * TRUE["coulomb"], est
    assert abs(est[3]) < 0.3, est
