"""The fleet results table (``OUT/results.parquet``, CONTRACT section 5): schema, per-bag parts
and atomic writes.

One row per bag and effect. Columns (CONTRACT + extras): ``bag`` (path relative to ROOT), ``url``,
``bag_hash`` (content hash, the resume key), ``machine``, ``start_time`` (UTC), ``plant``,
``effect`` (empty on a failed bag), ``in_model``, ``rank`` (position in the held-out ranking,
null for nominal effects), ``significant``, ``error_before``, ``error_after`` (held-out NRMSE,
fraction), ``p_value``, ``params`` (JSON text: name -> {"value", "stderr"}), ``model`` (final
model, effects joined by '+'), ``status`` (``ok`` or the one-line failure), ``seconds`` (task
wall time of the bag).

Each finished bag is written at once as ``OUT/parts/<bag_hash>.parquet`` (temp file + rename,
so a killed batch leaves only whole parts); :func:`consolidate` joins the parts of the bags of
one scan into ``results.parquet`` (again atomically).
"""
from __future__ import annotations

import os
from pathlib import Path

import pyarrow as pa
import pyarrow.parquet as pq

from ..errors import CablelabError

SCHEMA = pa.schema([
    ("bag", pa.string()), ("url", pa.string()), ("bag_hash", pa.string()), ("machine", pa.string()),
    ("start_time", pa.timestamp("us", tz="UTC")), ("plant", pa.string()), ("effect", pa.string()),
    ("in_model", pa.bool_()), ("rank", pa.int32()), ("significant", pa.bool_()),
    ("error_before", pa.float64()), ("error_after", pa.float64()), ("p_value", pa.float64()),
    ("params", pa.string()), ("model", pa.string()), ("status", pa.string()), ("seconds", pa.float64()),
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


def part_path(out, bag_hash: str) -> Path:
    return Path(out) / PARTS / f"{bag_hash}.parquet"


def write_part(out, bag_hash: str, rows: list[dict]) -> None:
    (Path(out) / PARTS).mkdir(parents=True, exist_ok=True)
    write_atomic(to_table(rows), part_path(out, bag_hash))


def done_hashes(out) -> dict[str, bool]:
    """bag_hash -> True if its part holds an ``ok`` result (False: a failed bag, retried)."""
    d = Path(out) / PARTS
    res = {}
    if not d.is_dir():
        return res
    for p in d.glob("*.parquet"):
        try:
            st = pq.read_table(p, columns=["status"]).column("status").to_pylist()
        except (OSError, pa.ArrowInvalid):
            continue  # unreadable part: the bag is redone
        res[p.stem] = bool(st) and all(s == "ok" for s in st)
    return res


def consolidate(out, refs_hashes: list[tuple[object, str]]) -> pa.Table:
    """``results.parquet`` from the parts of these bags (``(BagRef, hash)``, one part per hash;
    the same content found at two paths is listed under each path)."""
    tables = []
    for ref, h in refs_hashes:
        p = part_path(out, h)
        if not p.exists():
            continue
        t = pq.read_table(p, schema=SCHEMA)
        if t.num_rows and t.column("bag")[0].as_py() != ref.rel:
            n = t.num_rows
            t = t.set_column(0, "bag", pa.array([ref.rel] * n, pa.string()))
            t = t.set_column(1, "url", pa.array([ref.url] * n, pa.string()))
        tables.append(t)
    table = pa.concat_tables(tables) if tables else to_table([])
    write_atomic(table, Path(out) / RESULTS)
    return table


def read_results(path) -> pa.Table:
    """A results table (file or OUT directory)."""
    p = Path(path)
    if p.is_dir():
        p = p / RESULTS
    try:
        return pq.read_table(p)
    except (OSError, pa.ArrowInvalid) as exc:
        raise CablelabError(f"{p}: unreadable results table ({exc})") from None
