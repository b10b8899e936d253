"""Tiny benchmark harness: time a callable, print an aligned table, optionally JSON.

    from harness import Bench
    bench = Bench("bags", __doc__)          # parses --json (and whatever you add to bench.parser)
    args = bench.parse()
    best = bench.time(lambda: work(), repeat=3)   # seconds, best of repeat
    bench.row(case="write", messages=n, seconds=best, rate=n / best, unit="msg/s", target=">= 100000")
    bench.section("read")                    # optional: later rows go to a second table
    bench.done()                             # prints the table(s) (or one JSON object with --json)

Progress lines go to stderr so ``--json`` output stays clean.
"""
from __future__ import annotations

import argparse
import json
import sys
import time


def fmt(value) -> str:
    if isinstance(value, float):
        if value != value:  # NaN
            return "nan"
        if abs(value) >= 1000:
            return f"{value:,.0f}"
        if abs(value) < 1e-3 and value != 0:
            return f"{value:.3g}"
        return f"{value:.4g}"
    return str(value)


def table(rows: list[dict]) -> str:
    """Rows (dicts) as an aligned text table; columns in first-seen order."""
    cols: list[str] = []
    for r in rows:
        cols += [c for c in r if c not in cols]
    cells = [[fmt(r.get(c, "")) for c in cols] for r in rows]
    width = [max([len(c)] + [len(row[i]) for row in cells]) for i, c in enumerate(cols)]
    line = "  ".join(c.ljust(w) for c, w in zip(cols, width))
    out = [line, "  ".join("-" * w for w in width)]
    out += ["  ".join(v.rjust(w) if v[:1].isdigit() or v[:1] == "-" else v.ljust(w)
                      for v, w in zip(row, width)) for row in cells]
    return "\n".join(out)


class Bench:
    def __init__(self, name: str, description: str | None = None):
        self.name = name
        self.rows: list[dict] = []
        self.sections: list[tuple[str, list[dict]]] = [("", self.rows)]
        self.parser = argparse.ArgumentParser(prog=f"bench_{name}", description=description,
                                              formatter_class=argparse.RawDescriptionHelpFormatter)
        self.parser.add_argument("--json", action="store_true", help="print one JSON object")
        self.args = None

    def parse(self, argv=None):
        self.args = self.parser.parse_args(argv)
        return self.args

    @staticmethod
    def time(fn, repeat: int = 3) -> float:
        """Best wall time (s) of ``repeat`` calls of ``fn()``."""
        best = float("inf")
        for _ in range(repeat):
            t0 = time.perf_counter()
            fn()
            best = min(best, time.perf_counter() - t0)
        return best

    @staticmethod
    def log(msg: str) -> None:
        print(msg, file=sys.stderr, flush=True)

    def section(self, title: str) -> None:
        """Start a new table (rows with other columns read better apart)."""
        self.rows = []
        self.sections.append((title, self.rows))

    def row(self, **values) -> None:
        self.rows.append(values)
        self.log(f"[{self.name}] " + ", ".join(f"{k}={fmt(v)}" for k, v in values.items()))

    def done(self) -> None:
        sections = [(title, rows) for title, rows in self.sections if rows]
        if self.args is not None and self.args.json:
            print(json.dumps({"bench": self.name,
                              "rows": [dict(r, section=t) if t else r for t, rows in sections for r in rows]}))
        else:
            print("\n\n".join((f"{title}\n" if title else "") + table(rows) for title, rows in sections))
