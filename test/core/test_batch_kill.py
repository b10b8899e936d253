"""Robustness of `cablelab batch` to killed processes: SIGKILL of one Dask worker process
mid-batch (Dask reschedules its task) and SIGKILL of the whole batch (a re-run with the same OUT
resumes); in both cases no row is lost and none is duplicated."""
from __future__ import annotations

import json
import os
import signal
import subprocess
import sys
import time

import psutil
import pyarrow.parquet as pq
import pytest

from cablelab.plants.axis.fleet import write_fleet

MACHINES, DAYS = 6, 10
N_EFFECTS = 5  # axis: inertia, viscous, coulomb, offset, delay


@pytest.fixture(scope="module")
def fleet(tmp_path_factory):
    root = tmp_path_factory.mktemp("fleet")
    write_fleet(root, MACHINES, DAYS, duration=4.0)
    return root


def _cmd(root, out):
    return [sys.executable, "-m", "cablelab.cli", "batch", str(root), "-o", str(out), "--workers", "2",
            "--greedy", "--json"]


def _bags_written(out) -> int:
    """Bags whose rows are in a (whole) part file: parts hold every bag finished in ~1 s."""
    hashes = set()
    for p in (out / "parts").glob("*.parquet") if (out / "parts").is_dir() else ():
        try:
            hashes |= set(pq.read_table(p, columns=["bag_hash"]).column("bag_hash").to_pylist())
        except Exception:  # noqa: BLE001 - a part being renamed into place
            continue
    return len(hashes)


def _wait_parts(out, n, proc, timeout=120.0):
    t0 = time.monotonic()
    while time.monotonic() - t0 < timeout:
        if _bags_written(out) >= n:
            return
        if proc.poll() is not None:
            pytest.fail(f"batch ended before {n} bags were done: {proc.stderr.read()[-2000:]}")
        time.sleep(0.02)
    pytest.fail("batch made no progress")


def _check_complete(out):
    rows = pq.read_table(out / "results.parquet").to_pylist()
    assert all(r["status"] == "ok" for r in rows), [r["status"] for r in rows if r["status"] != "ok"]
    keys = [(r["bag"], r["effect"]) for r in rows]
    assert len(keys) == len(set(keys)), "duplicated rows"
    assert len({r["bag"] for r in rows}) == MACHINES * DAYS, "lost bags"
    assert len(rows) == MACHINES * DAYS * N_EFFECTS


def _workers(pid):
    return [c for c in psutil.Process(pid).children(recursive=True)
            if any("spawn_main" in part for part in c.cmdline())]


def test_worker_killed_mid_batch_loses_no_row(fleet, tmp_path):
    out = tmp_path / "out"
    proc = subprocess.Popen(_cmd(fleet, out), stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True)
    try:
        _wait_parts(out, 3, proc)
        workers = _workers(proc.pid)
        assert len(workers) >= 2, [w.cmdline() for w in workers]
        victim = workers[0]
        victim.send_signal(signal.SIGKILL)
        victim.wait(10)
        done_at_kill = _bags_written(out)
        assert done_at_kill < MACHINES * DAYS, "batch finished before the kill; make bags longer"
        stdout, stderr = proc.communicate(timeout=240)
    finally:
        if proc.poll() is None:
            proc.kill()
    assert proc.returncode == 0, stderr[-3000:]
    assert json.loads(stdout)["bags"] == MACHINES * DAYS
    _check_complete(out)
    # the re-run diagnoses nothing again and changes nothing
    p = subprocess.run(_cmd(fleet, out)[:-1], capture_output=True, text=True, timeout=240)
    assert p.returncode == 0 and "(0 diagnosed now" in p.stdout, p.stdout + p.stderr[-2000:]
    _check_complete(out)


def test_whole_batch_killed_then_rerun_resumes(fleet, tmp_path):
    out = tmp_path / "out"
    proc = subprocess.Popen(_cmd(fleet, out), stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True,
                            start_new_session=True)
    try:
        _wait_parts(out, 5, proc)
        os.killpg(proc.pid, signal.SIGKILL)
        proc.wait(30)
    finally:
        if proc.poll() is None:
            proc.kill()
    done = _bags_written(out)
    assert 5 <= done < MACHINES * DAYS
    p = subprocess.run(_cmd(fleet, out)[:-1], capture_output=True, text=True, timeout=240)
    assert p.returncode == 0, p.stderr[-3000:]
    ran = int(p.stdout.split("(")[1].split(" diagnosed")[0])
    assert ran <= MACHINES * DAYS - done
    _check_complete(out)


def test_sigterm_writes_every_finished_bag_then_rerun_does_only_the_rest(fleet, tmp_path):
    """SIGTERM (a scheduler's job kill, `kill PID`) of the batch: the bags finished by then are
    gathered and written before it exits, so the re-run diagnoses exactly the others."""
    out = tmp_path / "out"
    # one worker: the 60 short bags take several seconds after the first part (with two workers
    # on an idle machine the rest could finish before the signal arrived)
    cmd = _cmd(fleet, out)
    cmd[cmd.index("--workers") + 1] = "1"
    proc = subprocess.Popen(cmd, stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True)
    try:
        _wait_parts(out, 3, proc)
        proc.send_signal(signal.SIGTERM)
        _, stderr = proc.communicate(timeout=120)
    finally:
        if proc.poll() is None:
            proc.kill()
    assert proc.returncode != 0, "batch finished before the signal; make bags longer"
    assert "Traceback" not in stderr, stderr[-2000:]
    done = _bags_written(out)
    assert 3 <= done < MACHINES * DAYS
    p = subprocess.run(_cmd(fleet, out)[:-1], capture_output=True, text=True, timeout=240)
    assert p.returncode == 0, p.stderr[-3000:]
    assert f"({MACHINES * DAYS - done} diagnosed now" in p.stdout, (done, p.stdout)
    _check_complete(out)
