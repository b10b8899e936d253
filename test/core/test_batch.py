"""`cablelab batch` end to end on a synthetic fleet (6 machines x 10 days of winch bags from an
independent solve_ivp simulation, cablelab.plants.axis.fleet) with planted drifts: every drift is
found (machine, parameter, day within +-1), clean machines report none, a corrupt bag becomes one
failed row, and a re-run with the same OUT diagnoses nothing again and keeps every row once.
"""
from __future__ import annotations

import datetime as dt
import json
import os
import shutil
import subprocess
import sys

import pyarrow.parquet as pq
import pytest

from cablelab.fleet.scan import compile_group_by, content_hash, find_bags, match_group_by
from cablelab.plants.axis.fleet import day_time, machine_names, write_fleet
from cablelab.fleet.task import run_bag

MACHINES, DAYS = 6, 10
CONTRACT_COLUMNS = {"bag", "machine", "start_time", "plant", "effect", "significant", "error_before",
                    "error_after", "in_model", "params", "status"}


def _batch(root, out, *extra):
    cmd = [sys.executable, "-m", "cablelab.cli", "batch", str(root), "-o", str(out), "--workers", "2",
           "--json", *extra]
    p = subprocess.run(cmd, capture_output=True, text=True, timeout=300)
    assert p.returncode == 0, p.stderr[-3000:]
    return json.loads(p.stdout), p.stderr


@pytest.fixture(scope="module")
def fleet(tmp_path_factory):
    root = tmp_path_factory.mktemp("fleet")
    drifts = write_fleet(root, MACHINES, DAYS)
    bad = root / "winch-99" / "day-00"
    bad.mkdir(parents=True)
    (bad / "broken.mcap").write_bytes(b"not an mcap file at all")
    out = tmp_path_factory.mktemp("out")
    summary, stderr = _batch(root, out, "--greedy")
    return root, out, drifts, summary, stderr


def test_every_planted_drift_found_and_clean_machines_quiet(fleet):
    root, out, drifts, summary, _ = fleet
    assert len(drifts) == 2
    assert summary["bags"] == MACHINES * DAYS + 1 and summary["failed"] == 1
    found = summary["drift"]
    for d in drifts:
        hits = [f for f in found if f["machine"] == d.machine and f["param"] == d.param
                and f["effect"] == d.effect]
        assert hits, (d, found)
        since = dt.datetime.fromisoformat(hits[0]["since"].replace("Z", "+00:00"))
        want = day_time(d.first_changed_day, machine_names(MACHINES).index(d.machine))
        assert abs((since - want).total_seconds()) <= 86400 * 1 + 3600, (since, want)
    drifting = {d.machine for d in drifts}
    assert not [f for f in found if f["machine"] not in drifting], found


def test_results_table_has_contract_columns_and_one_row_per_bag_and_effect(fleet):
    root, out, _, _, _ = fleet
    t = pq.read_table(out / "results.parquet")
    assert CONTRACT_COLUMNS <= set(t.column_names)
    rows = t.to_pylist()
    ok = [r for r in rows if r["status"] == "ok"]
    assert len({r["bag"] for r in ok}) == MACHINES * DAYS
    keys = [(r["bag"], r["effect"]) for r in rows]
    assert len(keys) == len(set(keys))
    # every ok bag: the model's own effects and every candidate of the axis plant, once
    effects = {"axis_inertia", "joint_viscous_friction", "joint_coulomb_friction",
               "torque_sensor_offset", "time_delay"}
    for bag in {r["bag"] for r in ok}:
        assert {r["effect"] for r in ok if r["bag"] == bag} == effects
    for r in ok:
        assert r["machine"] == r["bag"].split("/")[0]  # description name
        assert r["plant"] == "axis"
        params = json.loads(r["params"])
        assert params and all({"value", "stderr"} <= set(v) for v in params.values())
    # the bag's own first stamp is its start time
    r0 = next(r for r in ok if r["bag"] == "winch-03/day-07")
    assert r0["start_time"] == day_time(7, 2)
    # the nominal model's mass is recovered on every bag (truth 2 kg +- 10 % per machine)
    masses = [json.loads(r["params"])["M"]["value"] for r in ok if r["effect"] == "axis_inertia"]
    assert min(masses) > 1.7 and max(masses) < 2.3
    bad = [r for r in rows if r["status"] != "ok"]
    assert len(bad) == 1 and bad[0]["bag"] == "winch-99/day-00" and "\n" not in bad[0]["status"]
    assert "broken.mcap" in bad[0]["status"] or "winch-99" in bad[0]["status"]


def test_report_and_progress(fleet):
    root, out, drifts, _, stderr = fleet
    html = (out / "index.html").read_text()
    assert "dashboard" in stderr and "http" in stderr  # dashboard link printed at start
    for d in drifts:
        assert d.machine in html
    for img in ("fig/heatmap.png", "fig/param_joint_coulomb_friction_Fc.png",
                "fig/param_torque_sensor_offset_OF.png"):
        assert f"src='{img}'" in html and (out / img).stat().st_size > 1000


def test_rerun_skips_done_bags_and_keeps_rows_once(fleet, tmp_path):
    root, out, _, summary, _ = fleet
    out2 = tmp_path / "out2"
    shutil.copytree(out, out2)
    parts = {p.name: p.stat().st_mtime_ns for p in (out2 / "parts").glob("*.parquet")}
    before = pq.read_table(out2 / "results.parquet").num_rows
    p = subprocess.run([sys.executable, "-m", "cablelab.cli", "batch", str(root), "-o", str(out2),
                        "--workers", "1", "--greedy"], capture_output=True, text=True, timeout=300)
    assert p.returncode == 0, p.stderr[-2000:]
    assert f"{MACHINES * DAYS + 1} bags (1 diagnosed now" in p.stdout  # only the failed bag again
    after = {p.name: p.stat().st_mtime_ns for p in (out2 / "parts").glob("*.parquet")}
    changed = [k for k in after if after[k] != parts.get(k)]
    assert len(changed) == 1
    assert pq.read_table(out2 / "results.parquet").num_rows == before


def test_scan_group_by_pattern_and_content_hash(fleet, tmp_path):
    root, _, _, _, _ = fleet
    refs = find_bags(root, "{machine}/day-*")
    assert len(refs) == MACHINES * DAYS + 1
    assert {r.machine for r in refs} == set(machine_names(MACHINES)) | {"winch-99"}
    rx = compile_group_by("{machine}/{date}/*")
    m, t = match_group_by(rx, "crane-7/2025-03-04/run1", "{machine}/{date}/*")
    assert m == "crane-7" and t == dt.datetime(2025, 3, 4, tzinfo=dt.timezone.utc)
    with pytest.raises(Exception, match="does not match --group-by"):
        match_group_by(rx, "crane-7", "{machine}/{date}/*")
    # same content at another path: same hash; one byte changed: another hash
    a = root / "winch-01" / "day-00"
    b = tmp_path / "copy"
    shutil.copytree(a, b)
    assert content_hash(str(a)) == content_hash(str(b))
    mcap = next(b.glob("*.mcap"))
    data = bytearray(mcap.read_bytes())
    data[len(data) // 2] ^= 0xFF
    mcap.write_bytes(bytes(data))
    assert content_hash(str(a)) != content_hash(str(b))


def test_task_never_raises_failures_are_one_line_rows(tmp_path):
    from cablelab.fleet.scan import BagRef

    (tmp_path / "empty").mkdir()
    (tmp_path / "empty" / "metadata.yaml").write_text("not: a bag\n")
    rows = run_bag(BagRef(str(tmp_path / "empty"), "empty"), "h0")
    assert len(rows) == 1 and rows[0]["status"] != "ok" and "\n" not in rows[0]["status"]
    assert "metadata" in rows[0]["status"]
    rows = run_bag(BagRef(str(tmp_path / "missing"), "missing"), "h1")
    assert len(rows) == 1 and rows[0]["status"] != "ok"


def test_missing_root_is_a_one_line_error(tmp_path):
    p = subprocess.run([sys.executable, "-m", "cablelab.cli", "batch", str(tmp_path / "nope"), "-o",
                        str(tmp_path / "o")], capture_output=True, text=True, timeout=60)
    assert p.returncode == 2 and "no such directory" in p.stderr and "Traceback" not in p.stderr
    assert len(p.stderr.strip().splitlines()) == 1


def test_bags_in_an_object_store_url_are_read_where_they_lie(fleet):
    """fsspec URL (the in-memory store stands in for s3:// etc.): found, hashed like the local
    copy, and diagnosed to the same rows as the local bag."""
    import fsspec

    root, _, _, _, _ = fleet
    mem = fsspec.filesystem("memory")
    local = root / "winch-01" / "day-03"
    for f in local.iterdir():
        mem.pipe(f"/fleetcopy/winch-01/day-03/{f.name}", f.read_bytes())
    refs = find_bags("memory://fleetcopy")
    assert [r.rel for r in refs] == ["winch-01/day-03"] and refs[0].url.startswith("memory://")
    h = content_hash(refs[0].url)
    assert h == content_hash(str(local))
    from cablelab.fleet.scan import BagRef

    remote_rows = run_bag(refs[0], h)
    local_rows = run_bag(BagRef(str(local), "winch-01/day-03"), h)
    assert [r["status"] for r in remote_rows] == ["ok"] * len(local_rows)
    for a, b in zip(remote_rows, local_rows):
        assert (a["effect"], a["params"], a["machine"], a["start_time"]) == \
            (b["effect"], b["params"], b["machine"], b["start_time"])


def test_existing_cluster_via_scheduler_gives_the_same_rows(fleet, tmp_path):
    """`dask scheduler` + `dask worker` started by hand (as on other hosts), then --scheduler."""
    import time

    root, out, _, _, _ = fleet
    sched_file = tmp_path / "scheduler.json"
    bindir = os.path.dirname(sys.executable)
    procs = [subprocess.Popen([os.path.join(bindir, "dask"), "scheduler", "--scheduler-file", str(sched_file),
                               "--port", "0", "--dashboard-address", ":0", "--host", "127.0.0.1"],
                              stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)]
    try:
        t0 = time.monotonic()
        while not sched_file.exists() and time.monotonic() - t0 < 60:
            time.sleep(0.1)
        address = json.loads(sched_file.read_text())["address"]
        procs.append(subprocess.Popen([os.path.join(bindir, "dask"), "worker", address, "--nworkers", "1",
                                       "--nthreads", "1", "--dashboard-address", ":0"],
                                      stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL))
        out2 = tmp_path / "out"
        p = subprocess.run([sys.executable, "-m", "cablelab.cli", "batch", str(root / "winch-04"), "-o",
                            str(out2), "--greedy", "--scheduler", address, "--json"],
                           capture_output=True, text=True, timeout=240)
    finally:
        for pr in reversed(procs):
            pr.terminate()
            try:
                pr.wait(20)
            except subprocess.TimeoutExpired:
                pr.kill()
    assert p.returncode == 0, p.stderr[-3000:]
    s = json.loads(p.stdout)
    assert s["bags"] == DAYS and s["failed"] == 0
    assert [(d["machine"], d["param"]) for d in s["drift"]] == [("winch-04", "OF")]
    mine = {(r["effect"], r["start_time"]): r["params"] for r in pq.read_table(out2 / "results.parquet").to_pylist()}
    local = {(r["effect"], r["start_time"]): r["params"] for r in pq.read_table(out / "results.parquet").to_pylist()
             if r["machine"] == "winch-04"}
    assert mine == local


def test_repository_bags_of_every_plant_match_the_diagnose_verb(tmp_path):
    """A tree of the repository's recorded bags (axis: real EMPS data, crane, cdpr): each row's
    ranking equals `cablelab diagnose --json` of that bag (the verb, run separately)."""
    from pathlib import Path

    repo_bags = Path(__file__).resolve().parents[2] / "bags"
    root = tmp_path / "bags"
    for name in ("emps", "crane_tilt", "cdpr_m2_fast"):
        shutil.copytree(repo_bags / name, root / name)
    out = tmp_path / "out"
    summary, _ = _batch(root, out)
    assert summary == {"bags": 3, "failed": 0, "drift": []}
    rows = pq.read_table(out / "results.parquet").to_pylist()
    assert {r["plant"] for r in rows} == {"axis", "crane", "cdpr"}
    for name in ("emps", "crane_tilt", "cdpr_m2_fast"):
        p = subprocess.run([sys.executable, "-m", "cablelab.cli", "diagnose", str(root / name), "--json"],
                           capture_output=True, text=True, timeout=120)
        assert p.returncode == 0, p.stderr
        verb = json.loads(p.stdout)
        mine = {r["effect"]: r for r in rows if r["bag"] == name}
        assert set(verb["baseline"]["effects"]) == {e for e, r in mine.items() if r["in_model"]}
        for v in verb["ranking"]:
            r = mine[v["effect"]]
            assert not r["in_model"] and r["significant"] == v["significant"]
            assert r["error_after"] == pytest.approx(v["error_after"], rel=1e-9)
            assert r["error_before"] == pytest.approx(verb["baseline"]["error"], rel=1e-9)
            got = {k: x["value"] for k, x in json.loads(r["params"]).items()}
            assert got == pytest.approx(v["params"], rel=1e-9)
