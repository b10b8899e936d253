"""The CDPR simulator node's stepping (plants/cdpr/stepping.py), without ROS or MuJoCo: a scripted
hardware records what was written, so the schedule, the lock-step matching, the brakes and the
counts are checked against the rules stated in the node's documentation."""
import numpy as np
import pytest

from cablelab.plants.cdpr.stepping import MAX_CATCH_UP, SimStepper
from cablelab.plants.cdpr.trajectory import ReferenceTable


class FakeSim:
    def __init__(self, rate):
        self.time, self.dt, self.added = 0.0, 1.0 / rate, []
        self.slack_now = False

    def slack(self):
        return np.array([self.slack_now, False])

    def add_mass(self, kg, model=True):
        self.added.append((self.time, kg))


class FakeHardware:
    def __init__(self, rate):
        self.sim = FakeSim(rate)
        self.command, self.writes, self.started = None, [], False

    def start(self):
        self.started = True

    def write(self, command):
        self.writes.append(("brake", self.command) if command is None else ("drive", command))
        self.sim.time = round(self.sim.time + self.sim.dt, 9)


def stepper(real_time, rate=100.0, **kw):
    hw = FakeHardware(rate)
    return SimStepper(hw, rate, real_time, lockstep_timeout=10.0, reference=ReferenceTable(rate), **kw), hw


def test_real_time_due_counts_late_and_dropped_steps():
    s, hw = stepper(True)
    assert hw.started
    assert s.due(100.0) == 0                      # sim time 0 at wall 100 s
    assert s.due(100.035) == 3 and s.late_steps == 0      # no command yet: nothing counted
    s.command(np.ones(2), None)
    for _ in range(3):
        s.step(100.035, fresh=True)
    assert s.k == 3 and s.due(100.0451) == 1 and s.late_steps == 0
    s.step(100.0451, fresh=True)
    assert s.due(100.0751) == 3 and s.late_steps == 2     # two ran a period or more late
    for _ in range(3):
        s.step(100.0751, fresh=True)
    assert s.due(100.0751 + 1.0) == MAX_CATCH_UP          # 100 due: 20 run, 80 dropped
    assert s.dropped_steps == 100 - MAX_CATCH_UP and s.late_steps == 2 + MAX_CATCH_UP - 1
    assert s.due(100.0751 + 1.0) == 0             # re-anchored: the dropped steps are not owed
    assert s.due(100.0751 + 1.0101) == 1


def test_real_time_brakes_hold_the_last_command_when_stale():
    s, hw = stepper(True)
    s.step(0.0, fresh=True)                       # no command yet: brakes, not a running fallback
    assert hw.writes[-1] == ("brake", None) and (s.fallbacks, s.fallbacks_running) == (1, 0)
    u = np.array([1.0, 2.0])
    s.command(u, 0.01)
    s.step(0.0, fresh=True)
    assert hw.writes[-1][0] == "drive" and np.array_equal(hw.writes[-1][1], u)
    assert s.command_age == [1, 0, 0] and s.missed_steps == 0
    s.step(0.0, fresh=True)                       # the same answer again: one period stale
    assert s.command_age == [1, 1, 0] and s.stale_command_steps == 1 and s.missed_steps == 1
    s.step(0.0, fresh=False)                      # timed out: the brakes hold what was commanded
    assert hw.writes[-1][0] == "brake" and np.array_equal(hw.writes[-1][1], u)
    assert s.fallbacks_running == 1 and s.missed_steps == 2


def test_a_step_ahead_is_the_deadline_step_published_at_its_deadline():
    """The step the answer to the last state drives, computed when the answer came, writes what
    the deadline would have written and is counted like it: on time at its deadline (the first
    step due then), fresh (command age one period); nothing goes ahead for an answer to another
    state, for a command naming none, twice, or in lock-step."""
    rate = 100.0
    fast, hw = stepper(True, rate)
    slow, hw2 = stepper(True, rate)
    for s in (fast, slow):
        assert s.due(100.0) == 0 and s.time_left(100.0) == pytest.approx(0.01)
    u = np.array([1.0, 2.0])
    for k in range(3):
        for s in (fast, slow):
            s.command(u + k, s.sim.time)             # the answer to the last published state
        assert fast.step_ahead(100.0 + k / rate + 0.004) and fast.ahead
        assert not fast.step_ahead(100.0 + k / rate + 0.005)      # one step ahead at most
        assert fast.due(100.0 + k / rate + 0.005) == 0            # its deadline has not come
        due = 100.0 + (k + 1) / rate + 0.0002
        assert fast.due(due) == 1 and slow.due(due) == 1          # then it is the step due
        slow.step(due, fresh=True)
        fast.published(due)
        slow.published(due)
        assert not fast.ahead and fast.sim.time == slow.sim.time
        assert [(w, list(c)) for w, c in hw.writes] == [(w, list(c)) for w, c in hw2.writes]
    assert fast.command_age == slow.command_age == [3, 0, 0] and fast.missed_steps == slow.missed_steps == 0
    assert fast.late_steps == 0 and fast.time_left(100.0 + 3 / rate) == pytest.approx(0.01)
    fast.command(u, fast.sim.time - 1 / rate)        # answers an older state
    assert not fast.step_ahead(100.04)
    fast.command(u, None)                            # names no state
    assert not fast.step_ahead(100.04) and len(hw.writes) == 3
    lock, _ = stepper(False)
    lock.command(u, 0.0)
    assert not lock.step_ahead(1.0)


def test_lock_step_waits_for_the_answer_then_times_out():
    s, hw = stepper(False)
    s.published(50.0)
    assert not s.step(50.0 + 9.9) and not hw.writes            # waits for the controller
    s.command(np.ones(2), 0.5)                                  # answers another state: still waits
    assert not s.step(50.0 + 9.9)
    s.command(np.full(2, 3.0), 0.0)                             # answers the state of sim time 0
    assert s.step(50.0 + 9.9) and hw.writes[-1][0] == "drive" and s.fallbacks == 0
    s.published(60.0)
    assert not s.step(65.0)
    assert s.step(70.1) and hw.writes[-1][0] == "brake" and s.fallbacks_running == 1
    assert s.missed_steps == 0                                  # (counted in real time only)
    s2, _ = stepper(False)                                      # commands naming no stamp: counted
    s2.published(0.0)
    assert not s2.step(1.0)
    s2.command(np.ones(2), None)
    assert s2.step(1.0)
    s2.published(1.0)
    assert not s2.step(1.5)                                     # one step per new command


def test_reference_stamps_lead_mass_change_and_duration():
    s, _ = stepper(True)                          # real time: 50 ms = five periods ahead
    before, after = s.reference_stamps(0.0)
    assert before == pytest.approx([0.0, 0.01, 0.02, 0.03, 0.04]) and after == pytest.approx([0.05])
    assert s.reference_stamps(0.01) == ([], [pytest.approx(0.06)])
    s, _ = stepper(True, rate=20.0)               # at least two periods
    assert s.reference_lead == pytest.approx(0.1)
    s, _ = stepper(True, reference_lead=0.02)     # as given
    assert s.reference_stamps(0.0) == ([0.0, pytest.approx(0.01)], [pytest.approx(0.02)])
    s, _ = stepper(False)                         # lock-step: each stamp before its state
    assert s.reference_stamps(0.5) == ([0.5], []) and s.reference_stamps(0.51) == ([0.51], [])
    s, _ = stepper(False, reference_lead=None)
    assert s.reference_stamps(0.5) == ([], [])
    seen = []
    s, hw = stepper(True, duration=0.05, mass_change=20.0, mass_change_time=0.03,
                    on_mass_change=seen.append)
    s.command(np.ones(2), None)
    while not s.done:
        s.step(0.0, fresh=True)
    assert hw.sim.added == [(pytest.approx(0.03), 20.0)] and seen == [20.0] and s.k == 5
    hw.sim.slack_now = True
    s.step(0.0, fresh=True)
    assert s.slack_steps == 1 and s.values()["slack cable steps"] == "1"


def test_steps_due_and_report_name_the_slack_cables():
    s, hw = stepper(False)
    assert s.steps_due(123.0) == 1                # lock-step: one step per timer (it may wait)
    hw.sim.truth_state = lambda: {"slack": np.array([False, True])}
    level, msg, values = s.report(0, "ok", {})
    assert (level, msg) == (1, "slack cable(s) 2") and values["mode"].startswith("as fast as possible")
    hw.sim.truth_state = lambda: {"slack": np.array([False, False])}
    assert s.report(2, "stale commands", {})[:2] == (2, "stale commands")   # nothing slack: kept
    r, _ = stepper(True)
    assert r.steps_due(100.0) == 0 and r.steps_due(100.025) == 2       # real time: the wall clock's


def test_from_parameters_builds_the_caroca_at_rest_at_point_a():
    """The simulator node's stepper from its parameter specs' defaults: the default description's
    cables, the s-curve's start (oracle: trajectory.pick_and_place at 0) as the initial pose, the
    reference published 50 ms ahead in real time, none with publish_reference false; a
    description without a cdpr section is one line naming the node."""
    from types import SimpleNamespace

    from cablelab.errors import CablelabError
    from cablelab.plants.cdpr.nodes.parameters import SIM
    from cablelab.plants.cdpr.sim import default_description
    from cablelab.plants.cdpr.trajectory import pick_and_place
    from cablelab.ros.params import check_all

    v = SimpleNamespace(**check_all(SIM, {"rate": 200.0}))
    desc = default_description()
    s = SimStepper.from_parameters(desc, v, "cable_sim_node")
    assert s.sim.n == len(desc.cdpr.cables) and s.rate == 200.0 and s.real_time
    np.testing.assert_allclose(s.sim.truth_pose()[0], pick_and_place(np.array([0.0])).position[0], atol=2e-3)
    assert s.reference_lead == pytest.approx(0.05) and s.publish_reference
    quiet = SimpleNamespace(**{**vars(v), "publish_reference": False})
    assert not SimStepper.from_parameters(desc, quiet).publish_reference
    with pytest.raises(CablelabError, match=r"^cable_sim_node --plant cdpr: the description has no cdpr section$"):
        SimStepper.from_parameters(SimpleNamespace(cdpr=None), v)
