"""Closed loop through DDS, real processes (own ROS_DOMAIN_ID via cablelab.ros.launch): the
suspended simulator (LiCAS truth plant: 4 length-limited tendons, arm torque motors, lock-step at
1 kHz), the swing estimator, the arm controller (PD + gravity, 000 Fig. 7 y excitation) and the
recorder. The recorded bag must show a stable loop with no control delay, the arms tracking the
excitation and the platform swinging, estimated as the simulator's truth says.

Oracles: the controller law recomputed from the recorded states and poses (lock-step: the torque
applied over each 1 ms period is the answer to the state that starts it), the Fig. 7 reference
formula, and the simulator's own ground-truth swing topic (exact pose geometry, no filter; the
simulator's IMU is on, so the estimator's yaw comes from it)."""
from __future__ import annotations

import sys
import time

import numpy as np

from cablelab.bags import open_bag
from cablelab.bags.reader import recorder_lost
from cablelab.plants.suspended.controller import ArmGravity, fig7_excitation, gains, pd_gravity
from cablelab.plants.suspended.params import parameter_set
from cablelab.rotations import quat_to_matrix, xyzw_to_wxyz

DURATION, RATE, START_X = 3.0, 1000.0, 0.05


def test_lockstep_closed_loop_sim_estimator_controller_recorder(launcher, tmp_path):
    p = parameter_set("licas")
    rest = [float(v) for v in np.array(p.S) - [0.0, 0.0, p.L]]
    bag_dir = tmp_path / "run"
    launcher.start("recorder", [sys.executable, "-m", "cablelab.cli", "record", "--plant", "suspended",
                                "-o", bag_dir, "--quiet"])
    launcher.node("estimator", "payload_estimator", "suspended",
                  {"rest_position": f"[{rest[0]!r}, {rest[1]!r}, {rest[2]!r}]", "rest_yaw": 0.0})
    launcher.node("controller", "pd_feedforward", "suspended", {"excitation": "y", "excitation_level": 1,
                                                                  "pose_sync": True})
    launcher.wait_for_subscribers(["/suspended/joint_states", "/suspended/platform_pose",
                                   "/suspended/effort_commands", "/suspended/swing_estimate"],
                                  timeout=120, node_name="cablelab_recorder")
    launcher.wait_for_subscribers(["/suspended/platform_pose"], timeout=120, node_name="payload_estimator")
    launcher.wait_for_subscribers(["/suspended/joint_states"], timeout=120, node_name="pd_feedforward")
    # time starts with the controller's first answer, after the recorder and the controller matched
    sim = launcher.node("sim", "cable_sim_node", "suspended",
                        {"model": "truth", "arm_input": "effort", "lockstep": True, "rate": RATE,
                         "wait_for_subscribers": 2, "duration": DURATION, "start_swing_x": START_X})
    t_wall = time.monotonic()
    assert sim.wait(900) == 0, sim.log()[-2000:]   # (lock-step: a loaded machine slows it down)
    wall = time.monotonic() - t_wall          # ran its duration and exited by itself
    n = int(DURATION * RATE)
    # time started only when every counted subscriber had acknowledged a state (not just been
    # counted on the simulator's side of the match, which can be seconds earlier on a busy
    # machine): the recorder gets every step; wait until the bag holds the end of the run
    # (the estimator answers the newest state of each of its polls: on a loaded machine it may
    # skip one, which is not a recording loss; the recorder's own lost counts are checked below)
    launcher.wait_for_recorded(bag_dir, {"/suspended/joint_states": n, "/suspended/swing_estimate": int(0.9 * n),
                                         "/suspended/ground_truth/swing": n}, timeout=300)
    deadline = time.monotonic() + 60
    while open_bag(bag_dir, recover=True).joint_state("/suspended/joint_states").t.max() < DURATION - 1e-6:
        assert time.monotonic() < deadline, "the end of the run never reached the bag"
        time.sleep(0.5)
    codes = launcher.stop_all()
    assert codes == {"sim": 0, "controller": 0, "estimator": 0, "recorder": 0}, codes

    lost = recorder_lost(bag_dir)
    assert lost is not None and not any(lost.values()), lost   # nothing published was lost
    bag = open_bag(bag_dir)
    js = bag.joint_state("/suspended/joint_states")
    _, first = np.unique(js.t, return_index=True)          # (the start state may be resent)
    t, q, qd, eff = js.t[first], js.position[first], js.velocity[first], js.effort[first]
    assert js.names == [f"{s}_{i}" for s in ("left", "right") for i in range(1, 5)]
    # lock-step: every 1 ms period simulated once, none lost on the way to the bag, from the first
    # step on (the start state itself may be dropped by a subscriber that matched after it)
    assert t[-1] > DURATION - 1e-6 and t[0] <= 1.0 / RATE + 1e-9
    np.testing.assert_allclose(np.diff(t), 1.0 / RATE, atol=1e-9)

    # no control delay: the torque over the period ending at state k+1 is the law of state k, with
    # the attitude of the pose of the same stamp (pose_sync)
    pose = bag.pose("/suspended/platform_pose")
    pt, pfirst = np.unique(pose.t, return_index=True)
    i_pose = np.searchsorted(pt, t)
    assert np.allclose(pt[i_pose], t, atol=1e-9)
    kp, kd, lim = gains(p)
    grav = ArmGravity(p)
    q_ref, qd_ref = fig7_excitation(t, p, "y", 1)

    def law(k, j):
        R = quat_to_matrix(xyzw_to_wxyz(pose.quaternion[pfirst][max(j, 0)]))
        return pd_gravity(q[k], qd[k], q_ref[k], qd_ref[k], kp, kd, grav.torque(q[k], R), lim)
    same = np.array([np.allclose(eff[k + 1], law(k, i_pose[k]), rtol=0, atol=1e-9)
                     for k in range(len(t) - 1)])
    assert same.all(), np.flatnonzero(~same)[:10]

    # stable and tracking: arm joints 2 and 3 follow the Fig. 7 sinusoids (17 deg, 0.25 Hz) within
    # 10 % of the amplitude after the first 0.5 s, the other joints stay near 0, torques in limits
    late = t > 0.5
    amp = np.deg2rad(17.0)
    err = np.abs(q[late] - q_ref[late])
    assert err.max() < 0.1 * amp, err.max(axis=0)
    assert np.ptp(q[late, 1]) > 1.5 * amp                  # the arms really moved (3 s of a 4 s period)
    assert np.all(np.abs(eff) <= lim + 1e-9) and np.all(np.isfinite(qd)) and np.abs(qd).max() < 2.0

    # the platform swings (from the pushed start plus the arm excitation), and the live estimate
    # equals the simulator's ground truth at the same stamps (noiseless poses: same geometry)
    truth = bag.joint_state("/suspended/ground_truth/swing")
    est = bag.joint_state("/suspended/swing_estimate", names=truth.names)
    common, i_t, i_e = np.intersect1d(np.round(truth.t, 6), np.round(est.t, 6), return_indices=True)
    assert len(common) > 0.9 * len(t)
    # (yaw comes from the IMU, published with the pose: when DDS delivers the pose first, the
    # newest IMU sample, one or on a loaded machine a few periods old (within imu_max_lag), is
    # carried forward with its rate: 1e-7 rad per period idle, 1.8e-5 rad seen under load)
    tol = np.array([1e-4 if n == "yaw" else 1e-9 for n in truth.names])
    assert np.all(np.abs(est.position[i_e] - truth.position[i_t]) <= tol), \
        np.abs(est.position[i_e] - truth.position[i_t]).max(axis=0)
    sx = truth.position[i_t, truth.names.index("swing_x")]
    assert np.ptp(sx) > 1.5 * START_X                      # swinging, not at rest
    ry = truth.position[i_t, truth.names.index("r_y")]
    assert np.abs(ry).max() < 1.5 * p.L * START_X          # bounded: no instability
    print(f"tracking error max {err.max():.4f} rad (amplitude {amp:.3f}), swing_x ptp {np.ptp(sx):.4f} rad, "
          f"max |r_y| {np.abs(ry).max():.4f} m, max |tau| {np.abs(eff).max():.3f} N m, "
          f"wall {wall:.1f} s for {DURATION} s simulated (incl. start-up)")
