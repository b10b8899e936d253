"""CPU of the live model monitor (cablelab.monitor.ResidualMonitor, what ``model_monitor``
runs) per monitored sample, and of the CDPR 3D view per MarkerArray.

Plays a recorded CDPR run (bags/cdpr_m1_reference, 100 Hz) into the monitor as serialised
messages in stamp order, evaluating every --period s of stamps as the node's timer does, and
reports the process CPU time of the evaluations (calibration excluded) per monitored sample and
per second of stream (the fraction of one core the monitor takes at the plant's rate). The
marker rows build and encode the CDPR MarkerArray (what cable_sim_node publishes at 30 Hz).
"""
from __future__ import annotations

import sys
import time
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parent))
from harness import Bench  # noqa: E402

ROOT = Path(__file__).resolve().parents[1]


def main(argv=None) -> int:
    from cablelab.bags import open_bag
    from cablelab.markers import MarkerEncoder, marker_array_cdr
    from cablelab.monitor import MonitorModel, ResidualMonitor
    from cablelab.plants.cdpr.markers import cdpr_markers

    bench = Bench("monitor", __doc__)
    bench.parser.add_argument("--bag", default=str(ROOT / "bags" / "cdpr_m1_reference"))
    bench.parser.add_argument("--period", type=float, default=0.25, help="s between evaluations (0.25)")
    bench.parser.add_argument("--window", type=float, default=3.0, help="s conditioned per evaluation (3)")
    args = bench.parse(argv)
    bag = open_bag(args.bag)
    mon = ResidualMonitor("cdpr", bag.description, MonitorModel(()), window=args.window, calibrate=10.0)
    msgs = []
    for tp in mon.topics:
        if bag.has(tp):
            tn, raws = bag.raw(tp)
            msgs += [(int(a), tp, r) for a, r in zip(tn, raws)]
    msgs.sort(key=lambda m: m[0])
    step_ns = int(args.period * 1e9)
    nxt = msgs[0][0] + step_ns
    cpu, samples, evals = 0.0, 0, 0
    t_first = None
    for ns, tp, raw in msgs:
        mon.add(tp, raw)
        if ns >= nxt:
            nxt += step_ns
            was = mon.calibrated
            c0 = time.process_time()
            s = mon.step()
            dc = time.process_time() - c0
            if was and s is not None:
                cpu += dc
                samples += len(s.t)
                evals += 1
                t_first = s.t[0] if t_first is None else t_first
                t_last = s.t[-1]
    stream_s = float(t_last - t_first) if samples else float("nan")
    bench.row(case=f"monitor, window {args.window:g} s every {args.period:g} s", samples=samples,
              evaluations=evals, cpu_s=cpu, us_per_sample=1e6 * cpu / max(samples, 1),
              ms_per_evaluation=1e3 * cpu / max(evals, 1), core_fraction=cpu / stream_s)
    desc = bag.description
    frame = cdpr_markers(desc, np.array([0.1, 0.2, 1.0]), np.eye(3), np.full(8, 800.0))
    enc = MarkerEncoder(frame)
    n = 300
    c0 = time.process_time()
    for _ in range(n):
        enc.encode([1.0], [cdpr_markers(desc, np.array([0.1, 0.2, 1.0]), np.eye(3), np.full(8, 800.0))])
    tb = (time.process_time() - c0) / n
    c0 = time.process_time()
    for _ in range(30):
        marker_array_cdr(frame, 1.0)
    tg = (time.process_time() - c0) / 30
    bench.row(case="CDPR MarkerArray: build + MarkerEncoder", samples=n, evaluations=n, cpu_s=tb * n,
              us_per_sample=1e6 * tb, ms_per_evaluation=1e3 * tb, core_fraction=30 * tb)
    bench.row(case="  reference: rosbags serialize_cdr per array", samples=30, evaluations=30, cpu_s=tg * 30,
              us_per_sample=1e6 * tg, ms_per_evaluation=1e3 * tg, core_fraction=30 * tg)
    bench.done()
    return 0


if __name__ == "__main__":
    sys.exit(main())
