"""Fleet diagnosis (``cablelab batch``): every bag of every machine, on Dask distributed.

``scan`` finds bags, machine/time and content hashes; ``task`` turns one bag into result rows
(never raises); ``engine`` runs the tasks on a Dask LocalCluster or an existing scheduler with
progress, retries and resume; ``table`` is the parquet schema; ``drift`` the change-point test;
``report`` the fleet index.html. (A synthetic fleet of winch bags with planted drifts for tests and
benchmarks: :mod:`cablelab.plants.axis.fleet`.)
"""
from __future__ import annotations


def analyse(table, alpha: float | None = None):
    """``(rows, findings, tests)`` of a results table (:mod:`cablelab.fleet.drift`)."""
    from . import drift

    rows = table.to_pylist()
    series = drift.series_from_rows(rows)
    findings, tests = drift.detect(series, drift.ALPHA if alpha is None else alpha)
    return rows, findings, tests
