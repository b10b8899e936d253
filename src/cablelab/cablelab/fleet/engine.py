"""Run the per-bag task over a fleet on Dask distributed.

Default: a :class:`distributed.LocalCluster` sized to the machine (one single-threaded worker
process per core), started and stopped here; ``scheduler="tcp://HOST:8786"`` uses an existing
cluster instead. A task diagnoses a small group of bags one after the other (memory stays one
bag's; :func:`groups`: up to :data:`MAX_GROUP` bags per task while many remain, single bags at
the end); a task whose worker dies is rescheduled by Dask (``allowed-failures``); the tasks
never raise (failures are rows). Finished bags' rows are written to ``OUT/parts/`` once a second
and at exit, interrupt or SIGTERM (:class:`cablelab.fleet.table.PartWriter`), so a re-run with
the same OUT skips the bags already done and an interrupted batch resumes.

What the engine costs per bag beyond the bag's own diagnosis (``bench/bench_batch.py``; found
with py-spy on the client and worker processes): Dask's fixed cost per task in the scheduler,
client and worker event loops (shared by the bags of a group), one gather and one parquet part
per second instead of per bag, the client polling its futures' local state instead of a
coroutine and a thread wake-up per finished task (``as_completed``), and the LocalCluster's
periodic housekeeping, slowed by :data:`LOCAL_CONFIG`.
"""
from __future__ import annotations

import contextlib
import logging
import os
import signal
import sys
import threading
import time
from pathlib import Path

from ..errors import CablelabError
from . import table as _table
from .scan import content_hash, find_bags
from .task import run_bag


def default_workers() -> int:
    return max(1, len(os.sched_getaffinity(0)) if hasattr(os, "sched_getaffinity") else os.cpu_count() or 1)


#: Dask settings of the LocalCluster (scheduler, nannies, workers). The worker's statistical
#: profiler (a thread sampling the task's stack every 10 ms) competes for the GIL with the task.
#: The rest is housekeeping that burns CPU in every process all the time, idle or not: the
#: event-loop health tick every 20 ms per server (the largest part), the system monitor every
#: 0.5 s, the nanny's memory check every 0.1 s, work stealing (nothing to steal here: tasks are
#: queued on the scheduler, ``worker-saturation``, and the last ones are single bags).
#: ``bench/bench_batch.py --idle`` prints the idle CPU per second with Dask's defaults and these.
LOCAL_CONFIG = {
    "distributed.worker.profile.enabled": False,
    "distributed.admin.tick.interval": "1s",
    "distributed.admin.system-monitor.interval": "5s",
    "distributed.worker.memory.monitor-interval": "1s",
    "distributed.scheduler.work-stealing": False,
}


def start_client(scheduler: str | None = None, workers: int | None = None, *, quiet: bool = False,
                 config: dict | None = None):
    """``(client, cluster or None)``: a Dask client of a new LocalCluster (Dask settings
    :data:`LOCAL_CONFIG`, or ``config`` instead) or of ``scheduler``."""
    from distributed import Client, LocalCluster

    if scheduler:
        try:
            client = Client(scheduler, timeout="20s")
        except (OSError, TimeoutError) as exc:
            raise CablelabError(f"--scheduler {scheduler}: cannot connect ({exc})") from None
        return client, None
    import dask

    # Dask's default MALLOC_TRIM_THRESHOLD_=64 KiB makes glibc trim after every large numpy free,
    # which slows the allocation-heavy fit; a task holds one bag at a time, so memory stays
    # bounded without it. Single-threaded BLAS as Dask sets it (one worker process per core).
    env = {"OMP_NUM_THREADS": 1, "MKL_NUM_THREADS": 1, "OPENBLAS_NUM_THREADS": 1}
    settings = LOCAL_CONFIG if config is None else config
    with dask.config.set({"distributed.nanny.pre-spawn-environ": env, **settings}):
        cluster = LocalCluster(n_workers=workers or default_workers(), threads_per_worker=1,
                               processes=True, dashboard_address=":0", silence_logs=logging.CRITICAL)
    # (CRITICAL: what goes wrong in a bag is a failed row, a lost worker a retried task; at a
    # SIGTERM the workers' last heartbeat to the closed scheduler logged a traceback on stderr)
    return Client(cluster), cluster


def run_batch(root, out, *, effects=(), greedy: bool = False, folds: int = 5, scheduler: str | None = None,
              workers: int | None = None, group_by: str | None = None, reports: bool = False,
              progress: bool = True, client=None, max_group: int | None = None,
              strict: bool = False) -> dict:
    """Diagnose every bag under ``root`` into ``out`` (the dashboard link always goes to stderr,
    the progress bar when ``progress``); returns ``{"refs", "hashes", "ran",
    "skipped", "table", "seconds", "dashboard"}`` (the table: :mod:`cablelab.fleet.table`).
    ``max_group``: most bags per task (default :data:`MAX_GROUP`; 1: one task per bag).
    ``strict``: refuse a bag whose data do not determine every parameter (its row's status is
    the refusal) instead of holding those parameters with a warning (``--strict``).

    ``out`` may not be, contain or lie inside ``root``; an existing ``out`` must be empty or an
    earlier batch output (marker file); it is locked against a second batch for the run
    (:func:`cablelab.atomic.claim_output_dir`)."""
    from ..atomic import claim_output_dir, release_target

    out = Path(out)
    taken = claim_output_dir(out, inputs=[root], option="-o", verb="batch")
    try:
        return _run_batch(root, out, effects=effects, greedy=greedy, folds=folds, scheduler=scheduler,
                          workers=workers, group_by=group_by, reports=reports, progress=progress,
                          client=client, max_group=max_group, strict=strict)
    finally:
        if taken:
            release_target(out)


def _run_batch(root, out: Path, *, effects, greedy, folds, scheduler, workers, group_by, reports,
               progress, client, max_group, strict=False) -> dict:
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
        ran, failed = _run(client, todo, out, effects, greedy, folds, progress,
                           MAX_GROUP if max_group is None else max_group, strict)
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
#: how often the client looks at its futures (a scan of their local states; ``as_completed``
#: instead wakes the client's thread and runs a coroutine per finished task)
POLL_SECONDS = 0.1


def _hash_chunk(urls: list[str]) -> list[str]:
    return [content_hash(u) for u in urls]


def _hashes(client, urls: list[str]) -> list[str]:
    """Content hashes, computed on the workers where the bags lie, ``HASH_CHUNK`` bags a task."""
    chunks = [urls[i:i + HASH_CHUNK] for i in range(0, len(urls), HASH_CHUNK)]
    return [h for part in client.gather(client.map(_hash_chunk, chunks, pure=False)) for h in part]


#: most bags in one task (:func:`groups`); 1 = one task per bag
MAX_GROUP = 8
#: a group is at most 1 / (GUIDED x workers) of the bags still to hand out
GUIDED = 4


def groups(n: int, workers: int, max_group: int = MAX_GROUP) -> list[int]:
    """Sizes of the consecutive groups of ``n`` bags, one task each, guided self-scheduling:
    each group takes ``remaining // (GUIDED * workers)`` bags (1 to ``max_group``), so the
    first tasks are large (Dask's fixed cost per task, ~5 ms of CPU over scheduler, client and
    worker on the shared benchmark machine, is shared by up to ``max_group`` bags) and the last
    are single bags (the workers finish together: at most one bag of imbalance)."""
    sizes, left = [], n
    while left > 0:
        k = max(1, min(max_group, left // (GUIDED * max(1, workers))))
        sizes.append(k)
        left -= k
    return sizes


def run_bags(refs, hashes, reports, effects=(), greedy: bool = False, folds: int = 5,
             strict: bool = False) -> list[list[dict]]:
    """The task: :func:`~cablelab.fleet.task.run_bag` of each bag of a group, one after the
    other (memory stays one bag's); rows per bag."""
    return [run_bag(r, h, effects, greedy, folds, rep, strict) for r, h, rep in zip(refs, hashes, reports)]


def _failed_row(ref, h, exc) -> dict:
    msg = str(exc).splitlines()[0] if str(exc) else ""
    return {"bag": ref.rel, "url": ref.url, "bag_hash": h, "machine": ref.machine or "",
            "start_time": ref.start_time, "effect": "", "in_model": False,
            "status": f"{type(exc).__name__}: {msg}"}


@contextlib.contextmanager
def _sigterm_as_exit():
    """SIGTERM raises SystemExit (in the main thread) so that ``finally`` blocks flush results."""
    if threading.current_thread() is not threading.main_thread():
        yield
        return

    def handler(signum, frame):
        raise SystemExit(128 + signum)

    old = signal.signal(signal.SIGTERM, handler)
    try:
        yield
    finally:
        signal.signal(signal.SIGTERM, old)


def _n_workers(client) -> int:
    try:
        return max(1, sum(w.get("nthreads", 1) for w in client.scheduler_info()["workers"].values()))
    except Exception:  # noqa: BLE001 - only a sizing hint
        return 1


def _run(client, todo, out, effects, greedy, folds, progress, max_group=MAX_GROUP,
         strict=False) -> tuple[int, int]:
    """Run the bags of ``todo`` (``(ref, hash, report dir)``): one ``client.map`` of tasks of
    :func:`groups` of bags, finished tasks noticed by polling their futures' local state every
    :data:`POLL_SECONDS`, their results gathered and written as one part (:class:`PartWriter`)
    once a second and on the way out (also on an exception, Ctrl-C or SIGTERM)."""
    from distributed import wait
    from tqdm import tqdm

    if not todo:
        return 0, 0
    n = len(todo)
    refs, hashes, reps = (list(c) for c in zip(*todo))
    bounds, i = [], 0
    for k in groups(n, _n_workers(client), max_group):
        bounds.append((i, i + k))
        i += k
    keys = [f"cablelab-bags-{hashes[a]}-{b - a}-{os.urandom(4).hex()}" for a, b in bounds]
    span = dict(zip(keys, bounds))
    writer = _table.PartWriter(out)
    bar = tqdm(total=n, desc="bags", unit="bag", disable=not progress, file=sys.stderr)
    failed = 0
    pending: list = []  # finished, not yet gathered: results are fetched once per part
    since = None

    def take():
        nonlocal failed, pending, since
        wait(pending)  # a result lost with its worker since it finished is being recomputed
        good = [f for f in pending if f.status == "finished"]
        results = dict(zip((f.key for f in good), client.gather(good))) if good else {}
        for f in pending:
            a, b = span[f.key]
            if f.key in results:
                per_bag = results[f.key]
            else:  # e.g. KilledWorker after repeated deaths (the task itself never raises)
                exc = f.exception()
                per_bag = [[_failed_row(refs[i], hashes[i], exc)] for i in range(a, b)]
            for rows in per_bag:
                writer.add(rows)
                if any(r.get("status") != "ok" for r in rows):
                    failed += 1
        writer.flush()
        pending, since = [], None  # releases the gathered results on the workers

    try:
        with _sigterm_as_exit():
            left = client.map(run_bags, *zip(*[(refs[a:b], hashes[a:b], reps[a:b]) for a, b in bounds]),
                              effects=tuple(effects), greedy=greedy, folds=folds, strict=strict, key=keys,
                              pure=False)
            while left:
                time.sleep(POLL_SECONDS)
                now = [f for f in left if f.done()]
                if not now:
                    continue
                left = [f for f in left if not f.done()] if len(now) < len(left) else []
                pending += now
                since = since or time.monotonic()
                bar.update(sum(span[f.key][1] - span[f.key][0] for f in now))
                if not left or time.monotonic() - since >= writer.seconds:
                    take()
                    bar.set_postfix(failed=failed, refresh=False)
    finally:
        try:
            if pending:
                take()
        finally:
            writer.flush()
            bar.close()
    return n, failed


def run_loop(refs, hashes, *, effects=(), greedy: bool = False, folds: int = 5, out=None,
             strict: bool = False) -> list[dict]:
    """The same per-bag task in a plain Python loop (the benchmark's baseline); with ``out``, the
    rows are written once at the end as ``out/results.parquet``."""
    rows = []
    for ref, h in zip(refs, hashes):
        rows += run_bag(ref, h, tuple(effects), greedy, folds, None, strict)
    if out is not None:
        Path(out).mkdir(parents=True, exist_ok=True)
        _table.write_atomic(_table.to_table(rows), Path(out) / _table.RESULTS)
    return rows
