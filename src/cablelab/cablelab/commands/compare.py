"""``cablelab compare BAG [--effects a,b] --json``: measured vs model per channel."""
from __future__ import annotations

from .numeric import number
from ._workbench_args import (add_common, add_overlay_out, dump_json, flag_impossible, load_from_args,
                              param_line, with_warnings, write_overlay_out)

HELP = "compare the model (nominal effects + --effects, fitted) with the measurement per channel"


def add_arguments(p) -> None:
    add_common(p, "compare")
    p.add_argument("--segments", type=number(ge=1, le=1000, integer=True), default=5,
                   help="number of worst segments to list")
    add_overlay_out(p)


def run(args) -> int:
    from ..overlay import stage_from_fit
    from ..workbench import compare

    plant, _, ds, model = load_from_args(args, check_out=True)
    res = compare(ds, model, segments=args.segments)
    flag_impossible(args, model.effects, res.params)
    write_overlay_out(args, plant, ds, [stage_from_fit(None, ds, res.fit)])
    out = with_warnings(args, res.to_json())
    if args.json:
        print(dump_json(out))
        return 0
    print(f"plant {res.plant}, model {' + '.join(res.effects)}, {res.samples} samples")
    for ch, m in res.channels.items():
        pearson = "n/a" if m["pearson"] is None else f"{m['pearson']:.4f}"   # constant model output
        print(f"  {ch}: NRMSE {100 * m['nrmse']:.2f} %  fit {m['fit_percent']:.1f} %  pearson "
              f"{pearson}  MAE {m['mae']:.4g}  max {m['max_abs']:.4g}")
    for name, v in res.params.items():
        print(param_line(name, v))
    if res.free_run is not None:
        fr = res.free_run
        print(f"  free run ({fr['horizon_s']} s windows): {fr['channel']} NRMSE {100 * fr['nrmse']:.2f} %, "
              f"max {fr['max_abs']:.4g}")
    print("worst segments:")
    for s in res.worst_segments:
        print(f"  {s['channel']}: {s['t_start']:.3f}-{s['t_end']:.3f} s  NRMSE {100 * s['error']:.1f} %")
    if args.out:
        print(f"model overlay (measured, prediction, residual) written to {args.out}")
    return 0
