"""The fleet results table (``OUT/results.parquet``, CONTRACT section 5): schema, per-bag parts
and atomic writes.

One row per bag and effect. Columns (CONTRACT + extras): ``bag`` (path relative to ROOT), ``url``,
``bag_hash`` (content hash, the resume key), ``machine``, ``start_time`` (UTC), ``plant``,
``effect`` (empty on a failed bag), ``in_model``, ``rank`` (position in the held-out ranking,
null for nominal effects), ``significant``, ``error_before``, ``error_after`` (held-out NRMSE,
fraction), ``p_value``, ``params`` (JSON text: name -> {"value", "stderr"}), ``model`` (final
model, effects joined by '+'), ``status`` (``ok`` or the one-line failure), ``seconds`` (task
wall time of the bag), ``warnings`` (null, or the line naming the parameters the bag did not excite,
held at their description or neutral values; ``--strict`` refuses such a bag instead).

Finished bags are written in chunks: ``OUT/parts/<time_ns>-<pid>-<seq>.parquet`` holds the rows
of every bag finished since the previous part (the engine writes one per second of results and at
exit or interrupt, :class:`PartWriter`), each written to a temp file and renamed, so a killed
batch leaves only whole parts and loses at most the last second of results (those bags are
redone). A bag may appear in several parts (a failed bag retried by a re-run): the newest part
holding an ``ok`` result of it wins, else its newest part (:func:`latest`). :func:`consolidate`
joins the chosen rows of the bags of one scan into ``results.parquet`` (again atomically).
Parts of the earlier one-file-per-bag layout (``<bag_hash>.parquet``) are read the same way.
"""
from __future__ import annotations

import os
import time
from pathlib import Path

import numpy as np
import pyarrow as pa
import pyarrow.compute as pc
import pyarrow.parquet as pq

from ..errors import CablelabError

SCHEMA = pa.schema([
    ("bag", pa.string()), ("url", pa.string()), ("bag_hash", pa.string()), ("machine", pa.string()),
    ("start_time", pa.timestamp("us", tz="UTC")), ("plant", pa.string()), ("effect", pa.string()),
    ("in_model", pa.bool_()), ("rank", pa.int32()), ("significant", pa.bool_()),
    ("error_before", pa.float64()), ("error_after", pa.float64()), ("p_value", pa.float64()),
    ("params", pa.string()), ("model", pa.string()), ("status", pa.string()), ("seconds", pa.float64()), ("warnings", pa.string()),
])
PARTS = "parts"
RESULTS = "results.parquet"


def to_table(rows: list[dict]) -> pa.Table:
    """Rows (dicts; missing keys null) as a table of :data:`SCHEMA`."""
    cols = {f.name: [r.get(f.name) for r in rows] for f in SCHEMA}
    return pa.Table.from_pydict(cols, schema=SCHEMA)


def write_atomic(table: pa.Table, path) -> None:
    """Write parquet to ``path`` via a temp file in the same directory and a rename."""
    path = Path(path)
    tmp = path.with_name(f".{path.name}.{os.getpid()}.tmp")
    try:
        pq.write_table(table, tmp)
        os.replace(tmp, path)
    except OSError as exc:
        raise CablelabError(f"{path}: cannot write ({exc.strerror or exc})") from None
    finally:
        if tmp.exists():
            tmp.unlink()


class PartWriter:
    """Buffer finished bags' rows; write them as one part when the oldest buffered bag is
    ``seconds`` old (checked at :meth:`add`) and at :meth:`flush` (call it at exit and on
    interrupt). One part per second instead of one per bag: a part costs ~1 ms of CPU whatever
    its size."""

    def __init__(self, out, seconds: float = 1.0):
        self.dir = Path(out) / PARTS
        self.seconds = float(seconds)
        self.rows: list[dict] = []
        self.since: float | None = None
        self.seq = 0
        self.written = 0  # bags written so far

    def add(self, rows: list[dict]) -> None:
        """Rows of one finished bag."""
        if self.since is None:
            self.since = time.monotonic()
        self.rows += rows
        if time.monotonic() - self.since >= self.seconds:
            self.flush()

    def flush(self) -> None:
        if not self.rows:
            return
        self.dir.mkdir(parents=True, exist_ok=True)
        self.seq += 1
        path = self.dir / f"{time.time_ns():020d}-{os.getpid()}-{self.seq:06d}.parquet"
        write_atomic(to_table(self.rows), path)
        self.written += len({r["bag_hash"] for r in self.rows})
        self.rows, self.since = [], None


def _parts(out) -> list[Path]:
    """Part files, oldest first (modification time, then name)."""
    d = Path(out) / PARTS
    if not d.is_dir():
        return []
    paths = []
    for p in d.glob("*.parquet"):
        try:
            paths.append((p.stat().st_mtime_ns, p.name, p))
        except OSError:
            continue
    return [p for *_, p in sorted(paths)]


def latest(out, columns=None) -> pa.Table:
    """The rows of every bag in the parts of ``out``, one result per ``bag_hash``: of the parts
    holding that bag, the newest whose rows of it are all ``ok``, else the newest. An unreadable
    part is skipped (its bags are redone)."""
    tables = []
    for i, p in enumerate(_parts(out)):
        try:
            t = pq.read_table(p, columns=columns, schema=None if columns else SCHEMA)
        except (OSError, pa.ArrowInvalid):
            continue
        tables.append(t.append_column("_part", pa.array(np.full(t.num_rows, i, np.int64))))
    if not tables:
        empty = to_table([])
        return empty.select(columns) if columns else empty
    t = pa.concat_tables(tables)
    h = np.asarray(t.column("bag_hash").to_pylist(), dtype=object)
    part = t.column("_part").to_numpy()
    ok = np.asarray(pc.fill_null(pc.equal(t.column("status"), "ok"), False))
    keys = np.unique(h, return_inverse=True)[1]
    nk, npart = int(keys.max()) + 1, int(part.max()) + 1
    # per (bag, part): all rows ok?
    cell = keys * npart + part
    bad = np.zeros(nk * npart, bool)
    np.logical_or.at(bad, cell, ~ok)
    score = np.where(bad[cell], part, part + npart)  # an all-ok part beats any failed one; then newest
    best = np.full(nk, -1, np.int64)
    np.maximum.at(best, keys, score)
    keep = score == best[keys]
    return t.filter(pa.array(keep)).drop_columns(["_part"])


def done_hashes(out) -> dict[str, bool]:
    """bag_hash -> True if its result (:func:`latest`) is ``ok`` (False: a failed bag, retried)."""
    t = latest(out, ["bag_hash", "status"])
    res: dict[str, bool] = {}
    for h, s in zip(t.column("bag_hash").to_pylist(), t.column("status").to_pylist()):
        res[h] = res.get(h, True) and s == "ok"
    return res


def consolidate(out, refs_hashes: list[tuple[object, str]]) -> pa.Table:
    """``results.parquet`` from the parts: the result of each of these bags (``(BagRef, hash)``,
    in this order; the same content found at two paths is listed under each path)."""
    t = latest(out)
    rows_of: dict[str, list[int]] = {}
    for i, h in enumerate(t.column("bag_hash").to_pylist()):
        rows_of.setdefault(h, []).append(i)
    take, bag, url = [], [], []
    for ref, h in refs_hashes:
        idx = rows_of.get(h, [])
        take += idx
        bag += [ref.rel] * len(idx)
        url += [ref.url] * len(idx)
    table = t.take(pa.array(take, pa.int64()))
    table = table.set_column(0, "bag", pa.array(bag, pa.string()))
    table = table.set_column(1, "url", pa.array(url, pa.string()))
    write_atomic(table, Path(out) / RESULTS)
    return table
