"""Workbench speed on the EMPS bag (24 841 samples): load, identify, compare, diagnose with 4
candidates x 5 folds (target < 5 s), greedy, report (target < 10 s).

Run: ./run python bench/bench_workbench.py [--repeat N] [--skip-report]
Prints a table (best and median of N runs, wall-clock seconds) for docs/benchmarks.md.
"""
from __future__ import annotations

import argparse
import os
import sys
import tempfile
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
BAG = ROOT / "bags" / "emps"


CPU = {}


def timed(fn, repeat):
    """(best wall, median wall, result); the best run's CPU time is kept in CPU[id(result)]."""
    times, cpus, out = [], [], None
    for _ in range(repeat):
        t0, c0 = time.perf_counter(), time.process_time()
        out = fn()
        times.append(time.perf_counter() - t0)
        cpus.append(time.process_time() - c0)
    CPU["last"] = min(cpus)
    times.sort()
    return times[0], times[len(times) // 2], out


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__)
    ap.add_argument("--repeat", type=int, default=3)
    ap.add_argument("--skip-report", action="store_true")
    args = ap.parse_args()

    from cablelab.workbench import build_model, compare, diagnose, identify_report, load

    rows = []

    class Rows(list):
        def append(self, row):  # add the CPU seconds of the step just timed
            super().append(row[:4] + (CPU["last"],) + row[4:])

    rows = Rows()
    best, med, (plant, desc, ds) = timed(lambda: load(BAG), args.repeat)
    rows.append(("load + condition bag", ds.n, best, med, "", ""))
    nominal = build_model(plant, desc)
    full = build_model(plant, desc, ["joint_coulomb_friction", "torque_sensor_offset"])
    best, med, out = timed(lambda: identify_report(ds, full), args.repeat)
    rows.append(("identify M,Fv,Fc,OF (+5-fold CV)", ds.n, best, med, "",
                 f"held-out NRMSE {100 * out.quality.cv_nrmse:.2f} %"))
    best, med, out = timed(lambda: compare(ds, full), args.repeat)
    rows.append(("compare (+ free run)", ds.n, best, med, "",
                 f"free-run pos. NRMSE {100 * out.free_run['nrmse']:.2f} %"))
    inertia_only = build_model(plant, desc, baseline=("axis_inertia",))
    cands = [c for c in plant.candidates(desc) if c not in inertia_only.effects]
    best, med, out = timed(lambda: diagnose(ds, inertia_only, cands, folds=5), args.repeat)
    rows.append((f"diagnose {len(cands)} candidates x 5 folds", ds.n, best, med, "< 5 s",
                 f"first: {out.ranking[0].effect}"))
    best, med, out = timed(lambda: diagnose(ds, nominal, plant.candidates(desc), folds=5), args.repeat)
    rows.append(("diagnose nominal (3 candidates)", ds.n, best, med, "",
                 f"first: {out.ranking[0].effect}"))
    best, med, out = timed(lambda: diagnose(ds, nominal, plant.candidates(desc), folds=5,
                                            greedy_mode=True), args.repeat)
    rows.append(("diagnose --greedy", ds.n, best, med, "",
                 f"final NRMSE {100 * out.final.error:.2f} %"))
    if not args.skip_report:
        from cablelab.report import build_report

        with tempfile.TemporaryDirectory() as tmp:
            def report():
                d = diagnose(ds, nominal, plant.candidates(desc), folds=5, greedy_mode=True)
                return build_report(ds, d, os.path.join(tmp, "r"))

            best, med, out = timed(report, args.repeat)
        rows.append(("report (greedy + 6 PNG + html)", ds.n, best, med, "< 10 s",
                     f"{len(out.figures)} figures"))

    print(f"workbench benchmark on {BAG.relative_to(ROOT)} ({args.repeat} runs, {os.cpu_count()} cores, "
          f"load average {os.getloadavg()[0]:.2f})")
    print(f"| {'step':<36} | {'samples':>7} | {'best [s]':>8} | {'median [s]':>10} | {'CPU [s]':>7} "
          f"| {'target':>6} | note |")
    print(f"|{'-' * 38}|{'-' * 9}|{'-' * 10}|{'-' * 12}|{'-' * 9}|{'-' * 8}|------|")
    for name, n, b, m, cpu, target, note in rows:
        print(f"| {name:<36} | {n:>7} | {b:>8.2f} | {m:>10.2f} | {cpu:>7.2f} | {target:>6} | {note} |")
    return 0


if __name__ == "__main__":
    sys.exit(main())
