"""The leg's experiment-design loop closed over DDS (the demo's step, :mod:`cablelab.plants.leg.demo`):
low hops with a hidden 2.7 N preload confound F0 with m while m is free; ``cablelab excite``
designs an apex-height schedule; the simulator (preload hidden, lock-step), the estimator, the
controller playing the schedule (``reference_bag``) and the recorder run as separate processes;
on the recorded run ``diagnose`` with the weighed mass ranks ``spring_preload`` first and
significant and brings F0 back within 10 %.

Oracle: the preload the simulator node was given (``preload`` parameter), the reference bag the
controller was given, and the ROS-free loop (:func:`cablelab.plants.leg.excite.closed_loop`: the
same plant, estimator and controller in one process) playing that reference: in lock-step the
recorded run is that run, sample for sample, from the start state on."""
from __future__ import annotations

import numpy as np

from cablelab.bags import open_bag
from cablelab.excite import get_exciter, read_reference
from cablelab.plants.leg import demo
from cablelab.plants.leg.excite import closed_loop
from cablelab.plants.leg.hybrid import LegParams
from cablelab.plants.leg.topics import GROUND_TRUTH, REFERENCE


def test_designed_schedule_over_dds_brings_the_preload_back(tmp_path, domain_id):
    loop = demo.close_loop(tmp_path, low_s=10.0, designed_s=8.0, domain=domain_id, max_iter=3)
    assert loop["condition_after"] < loop["condition_before"]
    # what the controller published on /leg/reference is the designed schedule
    played = open_bag(loop["designed"]).joint_trajectory(REFERENCE, ["apex_height"])
    want = read_reference(loop["reference"], REFERENCE, ["apex_height"])(played.t - played.t[0])[0]
    np.testing.assert_allclose(played.positions, want, atol=1e-9)
    lim = get_exciter("leg").limits(open_bag(loop["designed"]).description)
    assert played.positions.min() >= lim.lower[0] and played.positions.max() <= lim.upper[0]
    # lock-step from the first state: the controller answered every state, the estimator read each
    # sample with its own switch reading; the ROS-free loop gives the same heights
    truth = open_bag(loop["designed"]).joint_state(GROUND_TRUTH)
    once = np.r_[True, np.diff(truth.t) > 0]                # the start state, resent until answered
    t, z = truth.t[once], truth.position[once, 0]
    nominal = LegParams()
    ref = read_reference(loop["reference"], REFERENCE, ["apex_height"])
    offline = closed_loop(nominal.replace(F0=demo.LOOP_F0), lambda s: ref(s)[0][0, 0], float(t[-1]),
                          z0=nominal.z_td + 0.03, controller_params=nominal, seed=None)
    assert t[0] == 0.0 and len(t) == len(offline.t)
    np.testing.assert_allclose(z, offline.z, rtol=0, atol=1e-9)
    fit = demo.loop_fit(loop["designed"])
    assert fit["n"] > 7000                                   # 1 kHz, lock-step: no sample lost
    assert fit["first"] == "spring_preload" and fit["significant"] and not fit["ambiguous_with"]
    assert abs(fit["F0"] / demo.LOOP_F0 - 1) < 0.10
    assert fit["error"][1] < 0.5 * fit["error"][0]
    # with the mass weighed the preload stands apart from a stance mass on this run
    assert fit["cond_weighed"] < 3.0
