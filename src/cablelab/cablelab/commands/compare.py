"""``cablelab compare BAG [--effects a,b] --json``: measured vs model per channel."""
from __future__ import annotations

from ._workbench_args import (add_common, dump_json, flag_impossible, load_from_args, param_line,
                              with_warnings)

HELP = "compare the model (nominal effects + --effects, fitted) with the measurement per channel"


def add_arguments(p) -> None:
    add_common(p)
    p.add_argument("--segments", type=int, default=5, help="number of worst segments to list")


def run(args) -> int:
    from ..workbench import compare

    _, _, ds, model = load_from_args(args)
    res = compare(ds, model, segments=args.segments)
    flag_impossible(args, model.effects, res["params"])
    out = with_warnings(args, res)
    if args.json:
        print(dump_json(out))
        return 0
    print(f"plant {out['plant']}, model {' + '.join(out['effects'])}, {out['samples']} samples")
    for ch, m in out["channels"].items():
        pearson = "n/a" if m["pearson"] is None else f"{m['pearson']:.4f}"   # constant model output
        print(f"  {ch}: NRMSE {100 * m['nrmse']:.2f} %  fit {m['fit_percent']:.1f} %  pearson "
              f"{pearson}  MAE {m['mae']:.4g}  max {m['max_abs']:.4g}")
    for name, v in out["params"].items():
        print(param_line(name, v))
    if "free_run" in out:
        fr = out["free_run"]
        print(f"  free run ({fr['horizon_s']} s windows): {fr['channel']} NRMSE {100 * fr['nrmse']:.2f} %, "
              f"max {fr['max_abs']:.4g}")
    print("worst segments:")
    for s in out["worst_segments"]:
        print(f"  {s['channel']}: {s['t_start']:.3f}-{s['t_end']:.3f} s  NRMSE {100 * s['error']:.1f} %")
    return 0
