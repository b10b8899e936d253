"""Run the per-bag task over a fleet on Dask distributed.

Default: a :class:`distributed.LocalCluster` sized to the machine (one single-threaded worker
process per core), started and stopped here; ``scheduler="tcp://HOST:8786"`` uses an existing
cluster instead. Every bag is one task (memory stays per bag); a task whose worker dies is
rescheduled by Dask (``allowed-failures``); the tasks never raise (failures are rows). Each
finished bag's rows are written at once as ``OUT/parts/<hash>.parquet``, so a re-run with the
same OUT skips the bags already done and an interrupted batch resumes.
"""
from __future__ import annotations

import logging
import os
import sys
import time
from pathlib import Path

from ..errors import CablelabError
from . import table as _table
from .scan import content_hash, find_bags
from .task import run_bag


def default_workers() -> int:
    return max(1, len(os.sched_getaffinity(0)) if hasattr(os, "sched_getaffinity") else os.cpu_count() or 1)


def start_client(scheduler: str | None = None, workers: int | None = None, *, quiet: bool = False):
    """``(client, cluster or None)``: a Dask client of a new LocalCluster or of ``scheduler``."""
    from distributed import Client, LocalCluster

    if scheduler:
        try:
            client = Client(scheduler, timeout="20s")
        except (OSError, TimeoutError) as exc:
            raise CablelabError(f"--scheduler {scheduler}: cannot connect ({exc})") from None
        return client, None
    import dask

    # Dask's default MALLOC_TRIM_THRESHOLD_=64 KiB makes glibc trim after every large numpy free,
    # which slows the allocation-heavy fit; one task holds one bag, so memory stays bounded
    # without it. Single-threaded BLAS as Dask sets it (one worker process per core). The
    # worker's statistical profiler (a thread sampling the task's stack every 10 ms) is off: it
    # competes for the GIL with the task.
    env = {"OMP_NUM_THREADS": 1, "MKL_NUM_THREADS": 1, "OPENBLAS_NUM_THREADS": 1}
    with dask.config.set({"distributed.nanny.pre-spawn-environ": env,
                          "distributed.worker.profile.enabled": False}):
        cluster = LocalCluster(n_workers=workers or default_workers(), threads_per_worker=1,
                               processes=True, dashboard_address=":0", silence_logs=logging.ERROR)
    return Client(cluster), cluster


def run_batch(root, out, *, effects=(), greedy: bool = False, folds: int = 5, scheduler: str | None = None,
              workers: int | None = None, group_by: str | None = None, reports: bool = False,
              progress: bool = True, client=None) -> dict:
    """Diagnose every bag under ``root`` into ``out`` (the dashboard link always goes to stderr,
    the progress bar when ``progress``); returns ``{"refs", "hashes", "ran",
    "skipped", "table", "seconds", "dashboard"}`` (the table: :mod:`cablelab.fleet.table`)."""
    out = Path(out)
    try:
        out.mkdir(parents=True, exist_ok=True)
    except OSError as exc:
        raise CablelabError(f"{out}: cannot create output directory ({exc.strerror})") from None
    refs = find_bags(root, group_by)
    t0 = time.monotonic()
    own = client is None
    cluster = None
    if own:
        client, cluster = start_client(scheduler, workers)
    try:
        dash = getattr(client, "dashboard_link", None)
        print(f"cablelab batch: {len(refs)} bags, Dask dashboard {dash}", file=sys.stderr)
        hashes = _hashes(client, [r.url for r in refs])
        done = _table.done_hashes(out)
        todo, seen = [], set()
        for ref, h in zip(refs, hashes):
            if done.get(h) or h in seen:
                continue
            seen.add(h)
            rep = str(out / "bags" / h) if reports else None
            todo.append((ref, h, rep))
        ran, failed = _run(client, todo, out, effects, greedy, folds, progress)
    finally:
        if own:
            client.close()
            if cluster is not None:
                cluster.close()
    tab = _table.consolidate(out, list(zip(refs, hashes)))
    return {"refs": refs, "hashes": hashes, "ran": ran, "failed_now": failed,
            "skipped": len(refs) - ran, "table": tab, "seconds": time.monotonic() - t0,
            "dashboard": dash}


HASH_CHUNK = 32


def _hash_chunk(urls: list[str]) -> list[str]:
    return [content_hash(u) for u in urls]


def _hashes(client, urls: list[str]) -> list[str]:
    """Content hashes, computed on the workers where the bags lie, ``HASH_CHUNK`` bags a task."""
    chunks = [urls[i:i + HASH_CHUNK] for i in range(0, len(urls), HASH_CHUNK)]
    return [h for part in client.gather(client.map(_hash_chunk, chunks, pure=False)) for h in part]


def _run(client, todo, out, effects, greedy, folds, progress) -> tuple[int, int]:
    from distributed import as_completed
    from tqdm import tqdm

    futs = {}
    for ref, h, rep in todo:
        f = client.submit(run_bag, ref, h, tuple(effects), greedy, folds, rep, pure=False,
                          key=f"cablelab-bag-{h}-{os.urandom(4).hex()}")
        futs[f] = (ref, h)
    bar = tqdm(total=len(todo), desc="bags", unit="bag", disable=not progress, file=sys.stderr)
    failed = 0
    try:
        for fut in as_completed(futs):
            ref, h = futs[fut]
            try:
                rows = fut.result()
            except Exception as exc:  # noqa: BLE001 - e.g. KilledWorker after repeated deaths
                rows = [{"bag": ref.rel, "url": ref.url, "bag_hash": h, "machine": ref.machine or "",
                         "start_time": ref.start_time, "effect": "", "in_model": False,
                         "status": f"{type(exc).__name__}: {str(exc).splitlines()[0] if str(exc) else ''}"}]
            _table.write_part(out, h, rows)
            if any(r.get("status") != "ok" for r in rows):
                failed += 1
            bar.update(1)
            bar.set_postfix(done=bar.n, failed=failed)
    finally:
        bar.close()
    return len(todo), failed


def run_loop(refs, hashes, *, effects=(), greedy: bool = False, folds: int = 5) -> list[dict]:
    """The same per-bag task in a plain Python loop (the benchmark's baseline)."""
    rows = []
    for ref, h in zip(refs, hashes):
        rows += run_bag(ref, h, tuple(effects), greedy, folds, None)
    return rows
