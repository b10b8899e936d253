"""The demo's busy-machine note counts only CPU used outside our process tree
(cablelab.ros.sim_progress): checked against the CPU a child of ours reports for itself."""
import subprocess
import sys
import time

import pytest

from cablelab.ros.sim_progress import LoadMeter, process_tree

pytestmark = pytest.mark.skipif(not sys.platform.startswith("linux"), reason="/proc")

BURN = ("import time\nt = time.process_time()\nend = time.monotonic() + 1.5\n"
        "while time.monotonic() < end:\n    pass\nprint(time.process_time() - t)\n")


def test_process_tree_has_our_children_and_not_init():
    child = subprocess.Popen([sys.executable, "-c", "import time; time.sleep(5)"])
    try:
        tree = process_tree()
        assert child.pid in tree and 1 not in tree
    finally:
        child.kill()
        child.wait()


def test_our_busy_child_is_ours_not_others():
    meter = LoadMeter()
    child = subprocess.Popen([sys.executable, "-c", BURN], stdout=subprocess.PIPE, text=True)
    time.sleep(0.2)
    meter.sample()
    t0 = time.monotonic()
    time.sleep(1.0)
    meter.sample()
    dt = time.monotonic() - t0
    out, _ = child.communicate(timeout=30)
    assert float(out) > 0.1                     # the child did burn CPU (by its own clock)
    # the child was running for the whole interval: its CPU in it is at most dt and it is
    # counted as ours (clock ticks are 10 ms: a few ticks of slack)
    assert meter.ours * dt > 0.5 * min(float(out), dt) - 0.05
    assert meter.ours <= meter.cores + 0.05
