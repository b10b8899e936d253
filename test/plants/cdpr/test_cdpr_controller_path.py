"""The pd_feedforward node's compiled state -> command path (csrc/controller_path.c) against its
oracles: LiveController.planned_law and prepare + law on the same states, references and
estimates; its thread answering joint states over DDS in the node, handing bad states and states
without a planned row to the Python path, which reports them on /diagnostics."""
from __future__ import annotations

import time

import numpy as np
import pytest
from hypothesis import given, settings, strategies as st

from cablelab import native
from cablelab.plants.cdpr.controller_path import BAD_STATE, NO_ROW, OK, ControllerPath
from cablelab.plants.cdpr.live import ControllerConfig, LiveController
from cablelab.plants.cdpr.sim import default_description
from cablelab.plants.cdpr.trajectory import pick_and_place

DESC = default_description()
DT = 1e-3


def _lib():
    lib = native.load("controller_path")
    if lib is None:
        pytest.skip(f"no compiled path: {native.unavailable_reason('controller_path')}")
    return lib


def _reference(t0: float, n: int):
    tt = t0 + DT * np.arange(n)
    return tt, pick_and_place(tt)


def _controllers(feedforward: bool = True):
    cfg = ControllerConfig(feedforward=feedforward, nominal_mass=366.0)
    return LiveController(DESC.cdpr, DESC.gravity, cfg), LiveController(DESC.cdpr, DESC.gravity, cfg)


@settings(max_examples=40, deadline=None)
@given(seed=st.integers(0, 2**31 - 1), t0=st.floats(0.0, 70.0), mass=st.one_of(st.none(), st.floats(200.0, 1000.0)),
       com=st.tuples(st.floats(-0.3, 0.3), st.floats(-0.3, 0.3)), est_age=st.floats(0.0, 4.0),
       feedforward=st.booleans(), q_spread=st.floats(0.0, 50.0))
def test_compiled_law_equals_planned_law_and_prepare_law(seed, t0, mass, com, est_age, feedforward, q_spread):
    """For states around the reference (and far from it: saturation, tension floor), a fresh,
    stale (older than estimate_timeout: nominal mass) or missing estimate, PDFF or PD: the C
    path's torques equal planned_law's to round-off and prepare + law's (the per-sample oracle)."""
    ctl, oracle = _controllers(feedforward)
    path = ControllerPath(_lib(), ctl)
    try:
        tt, tr = _reference(t0, 40)
        plan = ctl.plan(tt, tr.position, tr.velocity, tr.acceleration)
        assert path.put(plan) == len(tt)
        if mass is not None:        # (after the rows were put: an estimate changes no row)
            for c in (ctl, oracle):
                c.estimate(t0 - est_age, mass, np.array(com))
            path.estimate()
        rng = np.random.default_rng(seed)
        n = len(DESC.cdpr.cables)
        for i in range(0, len(tt), 3):
            q = plan.pd[i] / ctl.config.gains.kp * (ctl.config.gains.kp > 0) + rng.normal(0, 1 + q_spread, n)
            qd = rng.normal(0, 1 + q_spread / 10, n)
            rc, tau = path.law(tt[i], q, qd)
            assert rc == OK
            want = oracle.planned_law(plan, i, q.copy(), qd.copy())
            np.testing.assert_allclose(tau, want, rtol=1e-13, atol=1e-12)
            per_sample = oracle.update(tt[i], q, qd, tr.position[i], None, tr.velocity[i], tr.acceleration[i])
            np.testing.assert_allclose(tau, per_sample, rtol=1e-9, atol=1e-9)
            assert ctl.planned_status(tt[i]) == oracle.status
    finally:
        path.close()


def test_bad_states_and_missing_rows_are_not_answered_and_a_new_estimate_weighs_every_row():
    ctl, oracle = _controllers()
    path = ControllerPath(_lib(), ctl)
    try:
        tt, tr = _reference(5.0, 10)
        plan = ctl.plan(tt, tr.position, tr.velocity, tr.acceleration)
        path.put(plan)
        n = len(DESC.cdpr.cables)
        q, qd = np.full(n, -4000.0), np.zeros(n)
        for bad_q, bad_qd in ((np.r_[q[:-1], np.nan], qd), (q, np.r_[qd[:-1], np.inf]), (q[:-1], qd[:-1]),
                              (q, qd[:-1]), (q[:0], qd[:0])):
            assert path.law(tt[0], bad_q, bad_qd) == (BAD_STATE, None)
        assert path.law(float("nan"), q, qd) == (BAD_STATE, None)
        assert path.law(tt[-1] + DT, q, qd)[0] == NO_ROW            # not planned yet
        assert path.law(tt[0] + 0.4 * DT, q, qd)[0] == NO_ROW       # between two stamps
        # an invalid reference row is not put (the Python path says why)
        pos = tr.position.copy()
        pos[3] = np.nan
        bad = ctl.plan(tt + 1.0, pos, tr.velocity, tr.acceleration)
        assert path.put(bad) == len(tt) - 1 and path.law(tt[3] + 1.0, q, qd)[0] == NO_ROW
        # nor a row with a term that is not finite (planned_law would give NaN or inf there)
        inf = ctl.plan(tt + 2.0, tr.position, tr.velocity, tr.acceleration)
        inf.pd[2, 0], inf.friction[5, 1] = np.nan, np.inf
        assert path.put(inf) == len(tt) - 2
        assert path.law(tt[2] + 2.0, q, qd)[0] == NO_ROW and path.law(tt[5] + 2.0, q, qd)[0] == NO_ROW
        # a new estimate weighs the feedforward of the rows put before it, without putting them again
        q = plan.pd[6] / ctl.config.gains.kp        # on the reference: no saturation
        before = path.law(tt[6], q, qd)[1]
        np.testing.assert_allclose(before, oracle.planned_law(plan, 6, q.copy(), qd.copy()), rtol=1e-13, atol=1e-12)
        for c in (ctl, oracle):
            c.estimate(tt[0], 700.0, np.array([0.1, -0.05]))
        np.testing.assert_array_equal(path.law(tt[6], q, qd)[1], before)     # not told yet
        path.estimate()
        after = path.law(tt[6], q, qd)[1]
        assert np.abs(after - before).max() > 1e-3
        np.testing.assert_allclose(after, oracle.planned_law(plan, 6, q.copy(), qd.copy()), rtol=1e-13, atol=1e-12)
        # (the nominal mass once the estimate is older than estimate_timeout at the row's stamp)
        late = ctl.plan(tt + 10.0, tr.position, tr.velocity, tr.acceleration)
        assert path.put(late) == len(tt)
        assert oracle.status[-1][0] == 0
        np.testing.assert_allclose(path.law(tt[6] + 10.0, q, qd)[1], oracle.planned_law(late, 6, q.copy(), qd.copy()),
                                   rtol=1e-13, atol=1e-12)
        assert "nominal mass" in oracle.status[-1][1]
    finally:
        path.close()



def test_rows_and_estimates_rewritten_while_the_law_reads_them_are_never_mixed():
    """The law reads rows and the estimate without a lock (the C thread must never wait for
    Python's thread): while one thread keeps rewriting every row with plan A or plan B (same
    stamps) and the estimate with E1 or E2, every answer read from another thread is exactly
    planned_law of one plan with one estimate, never a mixture of a half-rewritten row."""
    import threading

    ctl = _controllers()[0]
    path = ControllerPath(_lib(), ctl)
    try:
        tt, tr = _reference(3.0, 40)
        plans = [ctl.plan(tt, tr.position + shift, tr.velocity, tr.acceleration) for shift in (0.0, 0.05)]
        oracles, weights = [], []
        for mass, com in ((366.0, (0.0, 0.0)), (800.0, (0.2, -0.1))):
            o = _controllers()[0]
            o.estimate(tt[0], mass, np.array(com))
            oracles.append(o)
            weights.append(o.estimate_weights())
        n = len(DESC.cdpr.cables)
        rng = np.random.default_rng(7)
        q = plans[0].pd / ctl.config.gains.kp + rng.normal(0, 2.0, (len(tt), n))
        qd = rng.normal(0, 0.5, (len(tt), n))
        want = np.array([[[o.planned_law(p, i, q[i].copy(), qd[i].copy()) for i in range(len(tt))] for o in oracles]
                         for p in plans])                               # (plan, estimate, stamp, n)
        assert np.abs(want[0] - want[1]).max() > 1e-3 and np.abs(want[:, 0] - want[:, 1]).max() > 1e-3
        stop = threading.Event()

        reps = 50       # A, B, A, ... in one call: the writer spends its time rewriting rows
        t_all = np.ascontiguousarray(np.tile(tt, 2 * reps))
        pd_all, ff_all, fric_all = (np.ascontiguousarray(np.concatenate([getattr(p, f) for p in plans] * reps))
                                    for f in ("pd", "ff", "friction"))
        ptr = [a.ctypes.data for a in (t_all, pd_all, ff_all, fric_all)]

        def rewrite():
            k = 0
            while not stop.is_set():
                assert path.lib.cp_put_rows(path.h, len(t_all), *ptr) == len(t_all)
                t_est, c = weights[k % 2]
                path.lib.cp_set_estimate(path.h, t_est, *map(float, c))
                k += 1

        writer = threading.Thread(target=rewrite)
        writer.start()
        seen, missing = np.zeros((2, 2), int), 0
        try:
            for k in range(20000):
                i = k % len(tt)
                rc, tau = path.law(tt[i], q[i], qd[i])
                if rc != OK:
                    missing += 1        # (a row being rewritten through every try: goes to Python)
                    continue
                match = np.all(np.abs(want[:, :, i] - tau) <= 1e-12 + 1e-13 * np.abs(tau), axis=-1)
                assert match.any(), f"stamp {tt[i]}: {tau} is no plan's answer with any estimate"
                seen += match
        finally:
            stop.set()
            writer.join()
        # a row the writer is rewriting at that instant counts as absent (its state would go to
        # Python): how often depends on when the writer is preempted, so only most reads must answer
        assert missing < 10000, missing
        assert (seen > 0).all(), seen     # both plans and both estimates were read while rewritten
    finally:
        path.close()

# ---------------------------------------------------------------------------------- DDS


def test_node_thread_answers_states_over_dds_and_reports_bad_ones(ros_context):
    """The node with its compiled path, fed references and estimates through its callbacks and
    joint states over DDS from another node: every good state is answered by the C thread with
    the oracle's torques (a fresh estimate, then, the estimator gone, the nominal mass with a
    WARN), a NaN or short state is handed to the Python path and reported on /diagnostics, a
    state without a planned reference is answered by the Python path as without compiled path."""
    import rclpy
    from rclpy.node import Node
    from sensor_msgs.msg import JointState
    from std_msgs.msg import Float64MultiArray

    from cablelab.plants.cdpr.nodes.controller import CdprController
    from cablelab.plants.cdpr import topics
    from cablelab.ros import convert
    from cablelab.ros.qos import stream_qos

    _lib()
    ctl = CdprController()
    peer = Node("peer")
    got = {}
    peer.create_subscription(Float64MultiArray, topics.EFFORT_COMMANDS,
                             lambda m: got.setdefault(convert.command_stamp(m), np.array(m.data)), stream_qos(1000))
    pub = peer.create_publisher(JointState, topics.JOINT_STATES, stream_qos(1000))
    winches = [f"winch_{i}" for i in range(1, 9)]
    try:
        ctl.on_description(convert.string_msg(DESC.to_yaml()))
        assert ctl.path is not None, ctl.path_problem
        oracle = LiveController(DESC.cdpr, DESC.gravity, ctl.controller.config)
        tt, tr = _reference(3.0, 60)
        for k in range(len(tt)):
            ctl.on_reference(convert.multidof_msg(tt[k], tr.position[k], [0, 0, 0, 1.0], tr.velocity[k], None,
                                                  tr.acceleration[k], None))
        ctl.on_estimate(convert.inertia_msg(tt[0], 600.0, [0.05, -0.02, 0.0]))
        oracle.estimate(tt[0], 600.0, np.array([0.05, -0.02]))
        plan = oracle.plan(tt, tr.position, tr.velocity, tr.acceleration)
        deadline = time.monotonic() + 30
        while pub.get_subscription_count() < 2 and time.monotonic() < deadline:   # the node's C subscription
            rclpy.spin_once(peer, timeout_sec=0.05)
        rng = np.random.default_rng(2)
        sent = {}

        def send(t, q, qd):
            pub.publish(convert.joint_state_msg(t, winches, q, qd, np.zeros(len(q))))
            end = time.monotonic() + 10
            while time.monotonic() < end:      # one at a time: the subscription keeps the last one
                rclpy.spin_once(peer, timeout_sec=0.01)
                ctl.on_timer()                  # takes what the thread handed over
                if round(t, 9) in {round(s, 9) for s in got} or ctl.path.stats()["handed_off"] > handed[0]:
                    break
            handed[0] = ctl.path.stats()["handed_off"]

        handed = [0]
        for k in range(0, 20):
            q, qd = rng.normal(-4000, 30, 8), rng.normal(0, 3, 8)
            sent[tt[k]] = oracle.planned_law(plan, k, q.copy(), qd.copy())
            send(tt[k], q, qd)
        # the estimator died: 2.5 s of stamps later the feedforward uses the nominal mass
        late = tt[20:] + 2.5
        plan2 = oracle.plan(late, tr.position[20:], tr.velocity[20:], tr.acceleration[20:])
        for k in range(len(late)):
            ctl.on_reference(convert.multidof_msg(late[k], tr.position[20 + k], [0, 0, 0, 1.0],
                                                  tr.velocity[20 + k], None, tr.acceleration[20 + k], None))
        for k in range(5):
            q, qd = rng.normal(-4000, 30, 8), rng.normal(0, 3, 8)
            sent[late[k]] = oracle.planned_law(plan2, k, q.copy(), qd.copy())
            send(late[k], q, qd)
        assert oracle.status[-1][0] == 1 and "nominal mass" in oracle.status[-1][1]
        for t, want in sent.items():
            assert round(t, 9) in {round(s, 9) for s in got}, t
            np.testing.assert_allclose(got[min(got, key=lambda s: abs(s - t))], want, rtol=1e-13, atol=1e-12)
        stats = ctl.path.stats()
        assert stats["commanded"] == len(sent) and stats["handed_off"] == 0
        level, msg, values = ctl.status()
        assert level >= 1 and "nominal mass" in msg and values["compiled path"] == "on"
        lat = np.array(ctl.latency.samples)     # the path's take -> published times: each includes its publish
        assert len(lat) == len(sent) and 0.0 < stats["publish_max_ms"] <= 1000.0 * lat.max()
        assert stats["publish_slow"] <= int((lat > 2e-4).sum())    # a slow publish is a slow answer
        assert values["command publishes over 0.2 ms"] == str(stats["publish_slow"])
        assert values["commands"] == str(len(sent)) and values["joint_states received"] == str(len(sent))

        # bad states: not answered by C, handed over, rejected and reported by the Python path
        n_cmd = len(got)
        send(late[5], np.r_[np.full(7, -4000.0), np.nan], np.zeros(8))
        send(late[6], np.full(7, -4000.0), np.zeros(7))
        assert ctl.path.stats()["handed_off"] == 2 and len(got) == n_cmd
        level, msg, values = ctl.status()
        assert level >= 1 and values["joint_states rejected"] == "2"
        assert "rejected messages on joint_states" in msg and "NaN" not in values.get("compiled path", "")
        # a state past the planned reference: handed over after the row wait; the Python path
        # commands it with the latest reference once sync_wait passed (as without compiled path)
        t_past = late[-1] + 5 * DT
        q, qd = rng.normal(-4000, 30, 8), rng.normal(0, 3, 8)
        send(t_past, q, qd)
        end = time.monotonic() + 5
        while round(t_past, 9) not in {round(s, 9) for s in got} and time.monotonic() < end:
            rclpy.spin_once(peer, timeout_sec=0.01)
            ctl.on_timer()
        assert round(t_past, 9) in {round(s, 9) for s in got}
        assert ctl.path.stats()["handed_off"] == 3
    finally:
        ctl.destroy_node()
        peer.destroy_node()


def test_references_far_ahead_go_to_the_thread_without_a_gap_or_a_repeat(ros_context):
    """References streamed far ahead of the states: after 100 of them the node plans in blocks
    and its compiled path's thread takes the references too; once the thread's samples overlap
    the node's own subscription's, that subscription goes. Every reference is taken exactly once
    (counted, queued, planned), and the rows of those only the thread took answer with the
    oracle's torques."""
    import rclpy
    from rclpy.node import Node
    from sensor_msgs.msg import JointState
    from trajectory_msgs.msg import MultiDOFJointTrajectory

    from cablelab.plants.cdpr.nodes.controller import CdprController
    from cablelab.plants.cdpr import topics
    from cablelab.ros import convert
    from cablelab.ros.qos import stream_qos

    _lib()
    ctl = CdprController()
    peer = Node("ref_peer")
    pub_js = peer.create_publisher(JointState, topics.JOINT_STATES, stream_qos(10))
    pub_ref = peer.create_publisher(MultiDOFJointTrajectory, topics.REFERENCE, stream_qos(1000))
    winches = [f"winch_{i}" for i in range(1, 9)]
    tt, tr = _reference(3.0, 2000)

    def ref(k):
        return convert.multidof_msg(tt[k], tr.position[k], [0, 0, 0, 1.0], tr.velocity[k], None,
                                    tr.acceleration[k], None)

    def wait(cond, what, timeout=30.0):
        end = time.monotonic() + timeout
        while not cond():
            assert time.monotonic() < end, what
            rclpy.spin_once(peer, timeout_sec=0.01)
            ctl.on_timer()

    try:
        ctl.on_description(convert.string_msg(DESC.to_yaml()))
        assert ctl.path is not None, ctl.path_problem
        wait(lambda: pub_js.get_subscription_count() >= 1, "the thread's state subscription")
        pub_js.publish(convert.joint_state_msg(tt[0], winches, np.full(8, -4000.0), np.zeros(8), np.zeros(8)))
        wait(lambda: ctl.path.stats()["last_taken"] == tt[0], "the thread taking a state")
        for k in range(50, 1100):               # 50 periods ahead of the state, through the callback
            ctl.on_reference(ref(k))
        assert ctl._in_blocks and ctl._follow and ctl._handover
        wait(lambda: pub_ref.get_subscription_count() >= 2, "the thread's reference subscription")
        for k in range(1100, 1200):             # both subscriptions get these: the node's goes
            pub_ref.publish(ref(k))
        wait(lambda: not ctl._handover, "the overlap of the two subscriptions")
        assert ctl._ref_sub is None and pub_ref.get_subscription_count() >= 1
        for k in range(1200, 2000):             # only the thread gets these
            pub_ref.publish(ref(k))
        wait(lambda: ctl._ref_t == tt[-1], "every reference taken")
        st = ctl.inputs.inputs["reference"]
        assert (st.received, st.rejected) == (2000 - 50, 0)
        assert ctl.path.stats()["references"] >= 800 and ctl.path.stats()["references_lost"] == 0
        assert ctl.stream.refs.newest == tt[-1]
        oracle = LiveController(DESC.cdpr, DESC.gravity, ctl.controller.config)
        plan = oracle.plan(tt, tr.position, tr.velocity, tr.acceleration)
        rng = np.random.default_rng(4)
        for k in range(1200, 2000, 7):
            q, qd = rng.normal(-4000, 30, 8), rng.normal(0, 3, 8)
            rc, tau = ctl.path.law(tt[k], q, qd)
            assert rc == OK, k
            np.testing.assert_allclose(tau, oracle.planned_law(plan, k, q.copy(), qd.copy()), rtol=1e-13, atol=1e-12)
    finally:
        ctl.destroy_node()
        peer.destroy_node()


@pytest.mark.parametrize("batches", [[(10, 15), (15, 26), (26, 31)],      # the ring behind the subscription
                                     [(10, 20), (20, 31)],                # level with it
                                     [(0, 5), (15, 26), (26, 31)]])       # no overlap first, then ahead
def test_the_handover_queues_each_reference_once(ros_context, batches):
    """Whatever the thread's ring holds when the node's subscription (which took stamps 0..19)
    goes, every reference stamp 0..30 is queued exactly once and in order: the ring's samples
    the subscription took are skipped, also when they reach the node a run after the handover."""
    from cablelab.plants.cdpr.nodes.controller import CdprController
    from cablelab.ros import convert, fastspin

    _lib()
    ctl = CdprController()
    try:
        ctl.on_description(convert.string_msg(DESC.to_yaml()))
        assert ctl.path is not None, ctl.path_problem
        tt, tr = _reference(6.0, 31)
        ring = np.column_stack([tt, np.ones(31), tr.position, np.tile([0, 0, 0, 1.0], (31, 1)), tr.velocity,
                                tr.acceleration])
        ctl._in_blocks = ctl._follow = ctl._handover = True       # as _plan_in_blocks leaves it
        fastspin.poll(ctl, ctl._ref_sub)
        for k in range(20):                                       # what the subscription took
            ctl.on_reference(convert.multidof_msg(tt[k], tr.position[k], [0, 0, 0, 1.0], tr.velocity[k], None,
                                                  tr.acceleration[k], None))
        queue = [ring[a:b] for a, b in batches]
        ctl.path.references = lambda: queue.pop(0) if queue else ring[:0]
        while queue:
            ctl._path_references()
        assert not ctl._handover and ctl._ref_sub is None
        queued = np.concatenate(ctl._unplanned)
        np.testing.assert_array_equal(queued[:, 0], tt)
        assert ctl.inputs.inputs["reference"].received == 31
    finally:
        ctl.destroy_node()


@pytest.mark.parametrize("compiled", [True, False])
def test_three_processes_answer_the_simulator_and_survive_the_estimator(launcher, diagnostics_seen, compiled):
    """cable_sim_node (real time) + payload_estimator + pd_feedforward as processes, with the
    compiled path and without (the Python path, the oracle): the simulator gets its commands, the
    feedforward takes the live mass; the estimator killed, the controller keeps commanding with
    the nominal mass and says so on /diagnostics (WARN), and exits cleanly."""
    if compiled:
        _lib()
    launcher.node("estimator", "payload_estimator", "cdpr", {"poll_period": 0.01})
    launcher.node("controller", "pd_feedforward", "cdpr", {"compiled_path": compiled, "estimate_timeout": 1.0})
    probe, seen = diagnostics_seen

    def diag(name):
        return seen.get(name, (None, "", {}, 0.0))

    def spin_until(cond, timeout, what):
        end = time.monotonic() + timeout
        while time.monotonic() < end:
            for p in ("controller", "sim"):
                if p in launcher.procs:
                    assert launcher.procs[p].alive(), launcher.procs[p].log()[-2000:]
            probe.executor.spin_once(timeout_sec=0.05)
            if cond():
                return
        raise AssertionError(f"timeout after {timeout} s waiting for {what}; pd_feedforward: "
                             f"{diag('pd_feedforward')}; sim: {diag('cable_sim_node')}")

    spin_until(lambda: "pd_feedforward" in seen and "payload_estimator" in seen, 120, "the nodes' diagnostics")
    launcher.node("sim", "cable_sim_node", "cdpr", {"rate": 250.0, "real_time": True, "payload_mass": 249.0,
                                                    "duration": 600.0, "settle": 1.0, "reference_lead": 0.1})

    def ctl():
        return diag("pd_feedforward")[2]

    def live_mass():
        m = ctl().get("feedforward mass kg", "-")
        return m != "-" and 500.0 < float(m) < 700.0     # 366 kg platform + 249 kg payload

    # (the estimate converges while the simulator settles; the controller low-pass filters it)
    spin_until(lambda: int(diag("cable_sim_node")[2].get("effort_commands received", "0")) > 250 and live_mass(),
               120, "commands and the live mass in the feedforward")
    assert ctl()["compiled path"] == ("on" if compiled else "off")
    if compiled:
        spin_until(lambda: int(ctl().get("commands from the compiled path", "0")) > 200, 60, "compiled commands")
        # the simulator streams the reference 100 ms (25 periods) ahead: after 100 of them the
        # node plans them in blocks and its thread takes them
        spin_until(lambda: int(ctl().get("references taken by the compiled path", "0")) > 250, 60,
                   "references taken by the compiled path's thread")
        assert ctl()["reference rejected"] == "0" and "references lost by the compiled path" not in ctl()
    launcher.kill("estimator")
    killed = time.monotonic()
    spin_until(lambda: diag("pd_feedforward")[0] == 1 and "nominal mass" in diag("pd_feedforward")[1]
               and diag("pd_feedforward")[3] > killed, 60, "a WARN about the stale estimate")
    before = int(ctl()["commands"])
    spin_until(lambda: int(ctl()["commands"]) > before + 250, 60, "more commands after the estimator died")
    if compiled:
        assert int(ctl()["commands from the compiled path"]) > before - int(ctl()["states handed to Python"])
    codes = launcher.stop_all()
    assert codes["controller"] == 0, launcher.procs["controller"].log()[-2000:]
