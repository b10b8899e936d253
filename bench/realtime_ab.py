"""Alternating A/B runs of the 1 kHz three-process CDPR loop: which node placement or parameter
costs it periods, measured against the C rcl pair in the same minutes.

Each round runs, one after the other, the C rcl pair (``bench_rcl_floor``'s simulator and
controller, when ``pair`` is named) and the three-process loop once per variant, ``--seconds``
each, with the bench's placement (``bench_realtime --idle-estimator --idle-python``: the
estimator in SCHED_IDLE, the simulator's and controller's Python threads in SCHED_IDLE once their
compiled threads run) plus the variant's node parameters. Variants: ``pair``, ``base`` (the
bench's placement alone), or ``NAME=JSON`` (node parameters by node, e.g.
``slow_estimator='{"estimator": {"poll_period": 1.0}}'``). Run it on an idle machine:

    ./run python bench/realtime_ab.py --seconds 30 --rounds 2 pair base \\
        slow_estimator='{"estimator": {"poll_period": 1.0}}'

Per run it prints the missed cycles (as ``bench_realtime``'s ``three_process.missed_cycles``
and ``floor.c_rcl_pair_missed``) and the simulators' state publishes over 0.2 ms (the
three-process simulator's joint states / tensions / reference; the pair's state topic); with
``--json`` one object ``{variant: [run, ...]}``.
"""
from __future__ import annotations

import json
import sys
import time
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parent))
from harness import Bench, table  # noqa: E402
from realtime_runs import closed_loop  # noqa: E402

IDLE_PYTHON = {"sim": {"python_idle": True}, "controller": {"python_idle": True}}


def variants(specs: list[str]) -> dict:
    """{name: node parameters (None for the C pair)} of the command line's variants."""
    out = {}
    for spec in specs:
        name, _, params = spec.partition("=")
        if name == "pair":
            out[name] = None
            continue
        try:
            extra = json.loads(params) if params else {}
        except json.JSONDecodeError as exc:
            raise SystemExit(f"realtime_ab: variant {name!r}: parameters are not JSON ({exc})")
        if not isinstance(extra, dict) or not all(isinstance(v, dict) for v in extra.values()):
            raise SystemExit(f"realtime_ab: variant {name!r}: parameters must be {{node: {{parameter: value}}}}")
        placement = {k: dict(v) for k, v in IDLE_PYTHON.items()}
        for node, p in extra.items():
            placement.setdefault(node, {}).update(p)
        out[name] = placement
    return out


def main(argv=None) -> int:
    bench = Bench("realtime_ab", __doc__)
    bench.parser.add_argument("variants", nargs="+", help="pair, base or NAME=JSON")
    bench.parser.add_argument("--seconds", type=float, default=30.0, help="steady state per run, s (30)")
    bench.parser.add_argument("--rounds", type=int, default=2, help="rounds of all variants (2)")
    args = bench.parse(argv)
    todo = variants(args.variants)
    built = None
    if "pair" in todo:
        from bench_realtime import build_floor

        built, why = build_floor(bench.log)
        if built is None:
            raise SystemExit(f"realtime_ab: no C pair: {why}")
    runs = {name: [] for name in todo}
    for r in range(max(1, args.rounds)):
        for name, placement in todo.items():
            t0 = time.time()
            if placement is None:
                from bench_rcl_floor import run_floor

                out = run_floor(*built, args.seconds, False, False, bench.log)
                row = {"missed": out["missed_cycles"], "slow state publishes": out.get("slow_state_publishes")}
            else:
                out = closed_loop(args.seconds, bench.log, {}, None, False, placement, True)
                row = {"missed": out["missed_cycles"], "dropped": out["dropped"],
                       "slow state publishes": out.get("sim_slow_publishes"),
                       "slowest publish ms": out.get("sim_publish_max_ms")}
            runs[name].append(row)
            bench.log(f"{time.strftime('%H:%M:%S')} round {r + 1} {name}: {row} ({time.time() - t0:.0f} s)")
    if args.json:
        print(json.dumps(runs))
        return 0
    print(table([{"variant": name, "round": i + 1, **row} for name, rows in runs.items()
                 for i, row in enumerate(rows)]))
    return 0


if __name__ == "__main__":
    sys.exit(main())
