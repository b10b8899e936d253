"""``cablelab batch ROOT [--effects a,b] [--greedy] [--strict] [--scheduler ADDRESS] -o OUT``: diagnose every
bag under ROOT on Dask distributed, write OUT/results.parquet and the fleet report OUT/index.html."""
from __future__ import annotations

from .numeric import number
from ._workbench_args import add_folds, add_json, add_strict, dump_json

HELP = "diagnose every bag under ROOT (Dask), results.parquet + fleet report with parameter drift"


def add_arguments(p) -> None:
    p.add_argument("root", help="directory tree (or fsspec URL, e.g. s3://bucket/fleet) of rosbag2 bags")
    p.add_argument("-o", "--out", required=True, metavar="OUT", help="output directory (re-use it to resume)")
    p.add_argument("--effects", metavar="A,B", default="",
                   help="effects added to each plant's nominal model (ids: docs/interface.md section 3)")
    p.add_argument("--greedy", action="store_true",
                   help="add significant effects one at a time; parameters from the final model")
    add_folds(p)
    add_strict(p)
    p.add_argument("--scheduler", metavar="ADDRESS", default=None,
                   help="existing Dask scheduler, e.g. tcp://HOST:8786 (default: a LocalCluster)")
    p.add_argument("--workers", type=number(ge=1, le=4096, integer=True), default=None, metavar="N",
                   help="LocalCluster worker processes (default: one per core)")
    p.add_argument("--group-by", metavar="PATTERN", default=None,
                   help="machine and date from the bag path relative to ROOT, e.g. '{machine}/{date}/*' "
                        "(default: description name and first stamp)")
    p.add_argument("--reports", action="store_true",
                   help="also write each bag's own `cablelab report` under OUT/bags/<hash>/")
    p.add_argument("--alpha", type=number(gt=0, lt=1), default=0.01, help="family-wise level of the drift tests")
    add_json(p)


def run(args) -> int:
    from ..errors import CablelabError

    if args.workers is not None and args.workers < 1:
        raise CablelabError(f"--workers {args.workers}: must be at least 1")
    from ..atomic import claim_output_dir, release_target

    # OUT is checked against ROOT and locked for the whole run (diagnosis and report)
    taken = claim_output_dir(args.out, inputs=[args.root], option="-o", verb="batch")
    try:
        return _run(args)
    finally:
        if taken:
            release_target(args.out)


def _run(args) -> int:
    from ..fleet import analyse
    from ..fleet.engine import run_batch
    from ..fleet.report import summary, write_report
    from ..effect_spec import parse_effect_list

    res = run_batch(args.root, args.out, effects=parse_effect_list(args.effects), greedy=args.greedy,
                    folds=args.folds, scheduler=args.scheduler, workers=args.workers,
                    group_by=args.group_by, reports=args.reports, progress=not args.json,
                    strict=args.strict)
    rows, findings, tests = analyse(res["table"], args.alpha)
    index = write_report(args.out, rows, findings, tests, root=str(args.root))
    out = summary(rows, findings)
    out["bags"] = len(res["refs"])
    if args.json:
        print(dump_json(out))
        return 0
    print(f"{out['bags']} bags ({res['ran']} diagnosed now, {res['skipped']} already done), "
          f"{out['failed']} failed, {res['seconds']:.1f} s; wrote {args.out}/results.parquet and {index}")
    if out.get("held"):
        print(f"  warning: {out['held']} bags do not excite every parameter (held at their description or "
              f"neutral values: the warnings column; --strict refuses them)")
    for d in out["drift"]:
        print(f"  drift: {d['machine']} {d['effect']} {d['param']} since {d['since']}")
    return 0
