"""``./run demo``: the main job: every plant that brings a demo part runs through real nodes over
DDS, then its analysis; finally a table per plant with the papers' numbers side by side and
``<out>/index.html`` linking every plant's page and report.

A plant's demo part is ``DEMO`` (a :class:`DemoPart`) in its package's ``demo`` module
(``plants/<plant>/demo.py``): ``record`` runs the nodes (main thread: rclpy wants it) and
``analyse`` the recorded bags (in a worker thread, overlapping the next part's DDS run). Parts run
in their ``order``; today: CAROCA (001, :mod:`cablelab.plants.cdpr.demo`) and the boom crane on a
hidden tilted base (002, :mod:`cablelab.plants.crane.demo`).

Options: ``--out DIR`` (default bags/demo), ``--skip-<plant>``, ``--quick`` (short runs: a smoke
test), ``--folds K``, and each part's own options (``--duration``, ``--skip-pd``,
``--crane-duration``; see ``./run demo --help`` and docs/demo.md).
"""
from __future__ import annotations

import argparse
import os
import sys
import time
from dataclasses import dataclass, field
from pathlib import Path
from typing import Callable


def log(msg: str) -> None:
    print(f"[demo] {msg}", file=sys.stderr, flush=True)


@dataclass
class PartResult:
    """What a plant's demo part shows: table rows ``[quantity, cablelab, paper]``, bags, the
    ``cablelab report`` index (``""`` when the part writes none), the plant page, the first effect
    the diagnosis found, analysis seconds."""

    rows: list = field(default_factory=list)
    bags: list = field(default_factory=list)
    report: str = ""
    page: str = ""
    first: str = ""
    seconds: float = 0.0


@dataclass(frozen=True)
class DemoPart:
    """One plant's part of the demo.

    Args:
        plant: plant name; title: heading of its table.
        order: parts run in increasing order.
        add_arguments: ``fn(argparse group)`` adding the part's own options.
        record: ``fn(out_dir, args) -> runs``: the DDS run(s) (main thread).
        analyse: ``fn(out_dir, args, runs) -> PartResult`` (may run in a worker thread).
        quick: ``fn(args)`` shortening the options for ``--quick``.
        subdir: the part's directory under ``--out`` ("" = ``--out`` itself).
        how: how its data are made (shown in its table's heading).
    """

    plant: str
    title: str
    order: int
    add_arguments: Callable
    record: Callable
    analyse: Callable
    quick: Callable = lambda args: None
    subdir: str = ""
    how: str = "sim + estimator + controller + recorder over DDS"


def demo_parts() -> list[DemoPart]:
    """The demo part of every plant that has one, in order."""
    from .registry import available_plants, plant_module

    parts = []
    for name in available_plants():
        try:
            mod = plant_module(name, "demo")
        except ModuleNotFoundError:
            continue
        part = getattr(mod, "DEMO", None)
        if part is not None:   # (no isinstance: under ``python -m`` this module is __main__)
            parts.append(part)
    return sorted(parts, key=lambda p: (p.order, p.plant))


#: the links of a plant's line in the index: label -> (PartResult field, what the target is)
INDEX_LINKS = {"demo page": ("page", "html"), "diagnosis report": ("report", "html")}


def part_links(part: PartResult, out=None) -> list[tuple[str, str]]:
    """``[(label, path)]`` of a part's index line: its page, its ``cablelab report`` when it has
    one of its own (an existing HTML page other than its demo page), then each existing bag
    (a directory, named by its path relative to ``out`` when given). A link is only ever made to
    a file of the kind its label names."""
    links, seen = [], set()
    for label, (key, kind) in INDEX_LINKS.items():
        path = str(getattr(part, key) or "")
        if path.endswith(f".{kind}") and os.path.isfile(path) and os.path.abspath(path) not in seen:
            seen.add(os.path.abspath(path))
            links.append((label, path))
    for b in part.bags:
        if os.path.isdir(b):
            name = os.path.relpath(b, out) if out is not None else os.path.basename(os.path.normpath(str(b)))
            links.append((f"bag {name}", str(b)))
    return links


def index_page(out: Path, parts: dict) -> str:
    """``out/index.html``: one table per plant (cablelab vs paper) linking each plant's pages
    (:func:`part_links`: every link says what it opens)."""
    import html

    body = ["<h1>cablelab demo</h1><p>Each plant ran as separate processes over DDS (simulator, "
            "estimator, controller, recorder); the analysis is <code>cablelab estimate / diagnose / "
            "report</code> on the recorded bags.</p>"]
    for title, part in parts.items():
        links = " | ".join(f"<a href='{html.escape(os.path.relpath(path, out))}'>{html.escape(label)}</a>"
                           for label, path in part_links(part, out))
        rows = "".join("<tr>" + "".join(f"<td>{html.escape(str(c))}</td>" for c in r) + "</tr>"
                       for r in part.rows)
        body.append(f"<h2>{html.escape(title)}</h2><p>{links}</p>"
                    f"<table border=1 cellpadding=4><tr><th>quantity</th><th>cablelab</th>"
                    f"<th>paper</th></tr>{rows}</table>")
    path = out / "index.html"
    path.write_text("<!DOCTYPE html><html><head><meta charset='utf-8'><title>cablelab demo</title>"
                    "</head><body style='font-family:sans-serif;max-width:1000px;margin:auto'>"
                    + "".join(body) + "</body></html>")
    return str(path)


def print_table(title: str, rows: list) -> None:
    w = max(len(r[0]) for r in rows)
    v = max(22, max(len(r[1]) for r in rows))
    print(f"\n{title}")
    print(f"{'quantity':<{w}}  {'cablelab':>{v}}  paper")
    for r in rows:
        print(f"{r[0]:<{w}}  {r[1]:>{v}}  {r[2]}")


def main(argv: list[str] | None = None) -> int:
    parts = demo_parts()
    p = argparse.ArgumentParser(prog="./run demo", description=__doc__.split("\n\n")[0])
    p.add_argument("--out", default="bags/demo", help="output directory (default bags/demo)")
    p.add_argument("--quick", action="store_true", help="short runs and 3 folds: a smoke test")
    p.add_argument("--folds", type=int, default=5)
    for part in parts:
        g = p.add_argument_group(part.title)
        g.add_argument(f"--skip-{part.plant}", action="store_true", help=f"leave out {part.plant}")
        part.add_arguments(g)
    a = p.parse_args(argv)
    if a.quick:
        a.folds = 3
        for part in parts:
            part.quick(a)
    chosen = [part for part in parts if not getattr(a, f"skip_{part.plant}")]
    from concurrent.futures import ThreadPoolExecutor

    from .errors import CablelabError

    t_start = time.monotonic()
    out = Path(a.out)
    out.mkdir(parents=True, exist_ok=True)
    results, errors = {}, []

    def attempt(title, fn, *args):
        try:
            return fn(*args)
        except (CablelabError, RuntimeError) as exc:
            errors.append(f"{title}: {exc}")
            return None

    with ThreadPoolExecutor(1) as pool:
        # each part's analysis (numpy, in a worker thread) overlaps the next part's DDS run (main
        # thread: rclpy wants it), so the demo takes about the time of the DDS runs
        futures = []
        for part in chosen:
            where = out / part.subdir if part.subdir else out
            runs = attempt(part.title, part.record, where, a)
            if runs is not None:
                futures.append((part, pool.submit(attempt, part.title, part.analyse, where, a, runs)))
        for part, fut in futures:
            res = fut.result()
            if res is not None:
                results[part.title] = (part, res)
    index = index_page(out, {t: r for t, (_, r) in results.items()}) if results else None
    for title, (part, res) in results.items():
        took = f" (analysis {res.seconds:.0f} s)" if res.seconds else ""
        print_table(f"{title}: {part.how}{took}", res.rows)
    print()
    for title, (_, res) in results.items():
        print(f"{title.split(' (')[0]}: bags {', '.join(str(b) for b in res.bags)}")
        for label, path in part_links(res):
            if not label.startswith("bag "):
                print(f"    {label + ':':<17} {os.path.abspath(path)}")
    if index:
        print(f"index:  {os.path.abspath(index)}")
    print(f"({time.monotonic() - t_start:.0f} s)")
    for e in errors:
        print(f"cablelab demo: error: {e}", file=sys.stderr)
    return 2 if errors else 0


if __name__ == "__main__":
    sys.exit(main())
