"""The shared lock-step handshake (cablelab.ros.lockstep) on a fake wall clock: what a simulator
does on each tick, which answers it applies, and the two start modes and the timeout."""
import math

from cablelab.ros.lockstep import ADVANCE, FREE, RESEND, WAIT, LockStep


def test_wait_first_waits_resends_and_applies_only_the_answer_to_the_latest_state():
    lock = LockStep(True, wait_first=True, resend=0.25)
    lock.published(0.0, now=100.0)
    assert lock.poll(100.1) == WAIT and lock.poll(100.3) == RESEND   # nobody answered yet
    lock.published(0.0, now=100.3)                                   # (resent)
    assert lock.offer(0.0) and lock.poll(100.31) == ADVANCE
    lock.published(0.01, now=100.32)
    assert not lock.offer(0.0)                  # second answer to the resent state: stale
    assert lock.stale_answers == 1 and lock.poll(100.33) == WAIT
    assert lock.offer(None) and lock.poll(100.34) == ADVANCE        # no stamp: answers the last
    lock.published(0.02, now=100.35)
    assert lock.offer(0.02 + 1e-9) and lock.poll(100.36) == ADVANCE  # stamps agree within 1 us
    lock.published(0.03, now=100.37)
    assert lock.poll(1e6) == RESEND             # timeout inf: waits for ever


def test_real_time_until_commands_flow_then_lock_then_timeout_back_to_real_time():
    lock = LockStep(True, wait_first=False, timeout=10.0)
    lock.published(0.0, now=0.0)
    assert lock.poll(0.01) == FREE              # no commands yet: real time
    lock.published(0.01, now=0.01)
    assert not lock.offer(0.0)                  # a late answer to an earlier state: not applied,
    assert lock.poll(0.02) == WAIT              # but commands flow: wait for the next answer
    assert lock.offer(0.01) and lock.poll(0.03) == ADVANCE
    lock.published(0.02, now=0.03)
    assert lock.poll(5.0) == WAIT and lock.poll(10.04) == FREE     # controller gone: real time
    lock.published(0.03, now=10.05)
    assert lock.poll(10.06) == FREE             # stays real time until commands flow again
    assert lock.offer(0.03) and lock.poll(10.07) == ADVANCE


def test_disabled_accepts_everything_and_never_waits():
    lock = LockStep(False, timeout=math.inf)
    lock.published(1.0, now=0.0)
    assert lock.offer(0.5) and lock.poll(0.0) == FREE and lock.stale_answers == 0
