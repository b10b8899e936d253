"""``cablelab report BAG -o DIR``: index.html with PNG plots of compare, diagnose and identify."""
from __future__ import annotations

from ._workbench_args import add_common, add_folds, dump_json, load_from_args

HELP = "write DIR/index.html with plots: waterfall, ranking, parameters, overlay, residuals"


def add_arguments(p) -> None:
    add_common(p)
    add_folds(p)
    p.add_argument("-o", "--out", required=True, metavar="DIR", help="output directory")


def run(args) -> int:
    from ..report import build_report

    plant, desc, ds, model = load_from_args(args)
    res = build_report(ds, model, plant.candidates(desc), args.out, folds=args.folds,
                       title=f"cablelab report: {desc.name or plant.name}", quiet=args.json)
    if args.json:
        print(dump_json({"index": res["index"], "figures": res["figures"], "seconds": res["seconds"],
                         "final": res["steps"][-1]["effects"], "error": res["steps"][-1]["error"]}))
    else:
        print(f"wrote {res['index']} ({len(res['figures'])} figures, {res['seconds']:.1f} s)")
    return 0
