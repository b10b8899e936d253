"""The fleet table's resume bookkeeping (cablelab.fleet.table) and the engine's grouping of bags
into tasks (cablelab.fleet.engine.groups), against what they promise: a bag's result is the
newest ``ok`` one among the parts holding it (else the newest), parts of the old one-file-per-bag
layout read the same way, every bag is handed out exactly once, and the last tasks are single
bags."""
from __future__ import annotations

import datetime as dt
import os
import time

import pyarrow.parquet as pq
import pytest

from cablelab.fleet import table as T
from cablelab.fleet.engine import MAX_GROUP, groups
from cablelab.fleet.scan import BagRef

T0 = dt.datetime(2026, 1, 1, tzinfo=dt.timezone.utc)


def _rows(h, status="ok", effects=("a", "b"), value=1.0):
    if status != "ok":
        return [{"bag": h, "url": h, "bag_hash": h, "machine": "m", "start_time": T0, "effect": "",
                 "in_model": False, "status": status}]
    return [{"bag": h, "url": h, "bag_hash": h, "machine": "m", "start_time": T0, "effect": e,
             "in_model": True, "error_before": value, "status": "ok"} for e in effects]


def _write(writer, *bags):
    for rows in bags:
        writer.add(rows)
    writer.flush()
    time.sleep(0.01)  # distinct modification times


def test_newest_ok_result_wins_and_failed_bags_are_retried(tmp_path):
    w = T.PartWriter(tmp_path, seconds=3600)
    _write(w, _rows("h1"), _rows("h2", "ValueError: bad"), _rows("h3", "boom"))
    assert T.done_hashes(tmp_path) == {"h1": True, "h2": False, "h3": False}
    # a re-run: h2 now ok, h3 fails again with another reason
    _write(T.PartWriter(tmp_path, seconds=3600), _rows("h2", value=2.0), _rows("h3", "boom again"))
    assert T.done_hashes(tmp_path) == {"h1": True, "h2": True, "h3": False}
    # a later failure never replaces an ok result
    _write(T.PartWriter(tmp_path, seconds=3600), _rows("h2", "late failure"))
    assert T.done_hashes(tmp_path)["h2"] is True
    refs = [(BagRef(f"/x/{h}", f"rel/{h}"), h) for h in ("h3", "h1", "h2")]
    t = T.consolidate(tmp_path, refs)
    rows = t.to_pylist()
    assert [r["bag"] for r in rows] == ["rel/h3", "rel/h1", "rel/h1", "rel/h2", "rel/h2"]
    assert [r["status"] for r in rows if r["bag_hash"] == "h3"] == ["boom again"]
    assert {r["error_before"] for r in rows if r["bag_hash"] == "h2"} == {2.0}
    assert pq.read_table(tmp_path / T.RESULTS).num_rows == 5
    assert len(list((tmp_path / T.PARTS).glob("*.parquet"))) == 3


def test_parts_of_the_one_file_per_bag_layout_are_read(tmp_path):
    (tmp_path / T.PARTS).mkdir()
    T.write_atomic(T.to_table(_rows("old1")), tmp_path / T.PARTS / "old1.parquet")
    T.write_atomic(T.to_table(_rows("old2", "x")), tmp_path / T.PARTS / "old2.parquet")
    (tmp_path / T.PARTS / "junk.parquet").write_bytes(b"not parquet")  # skipped, never fatal
    assert T.done_hashes(tmp_path) == {"old1": True, "old2": False}


def test_writer_flushes_by_age_and_writes_whole_parts(tmp_path):
    w = T.PartWriter(tmp_path, seconds=0.05)
    w.add(_rows("h1"))
    assert not (tmp_path / T.PARTS).exists()  # younger than 50 ms: buffered
    time.sleep(0.06)
    w.add(_rows("h2"))  # the oldest buffered bag is now older than 50 ms: one part, both bags
    parts = list((tmp_path / T.PARTS).glob("*.parquet"))
    assert len(parts) == 1 and w.written == 2 and not w.rows
    assert set(pq.read_table(parts[0]).column("bag_hash").to_pylist()) == {"h1", "h2"}
    assert not [p for p in os.listdir(tmp_path / T.PARTS) if p.endswith(".tmp")]


@pytest.mark.parametrize("n,workers", [(1, 1), (7, 2), (61, 2), (200, 1), (200, 2), (1000, 3),
                                       (10000, 800)])
def test_groups_hand_out_every_bag_once_and_end_with_single_bags(n, workers):
    g = groups(n, workers)
    assert sum(g) == n and all(1 <= k <= MAX_GROUP for k in g)
    assert g == sorted(g, reverse=True)  # guided: never growing
    # the last GUIDED x workers bags go out one per task: workers end within one bag
    tail = min(n, 4 * workers)
    assert g[-tail:] == [1] * tail
    assert groups(n, workers, max_group=1) == [1] * n
