"""``cablelab report BAG -o DIR``: index.html with PNG plots of compare, diagnose and identify.

The directory is written under a temporary name and moved into place when complete (see
:mod:`cablelab.atomic`): an existing DIR needs ``--overwrite``, DIR may not be the bag.
"""
from __future__ import annotations

import os
import time

from ._workbench_args import (add_common, add_folds, add_overwrite, dump_json, greedy_stages, load_from_args,
                              with_warnings, write_overlay_bag)

HELP = "write DIR/index.html with plots: waterfall, ranking, parameters, overlay, residuals"


def add_arguments(p) -> None:
    add_common(p, "report")
    add_folds(p)
    p.add_argument("-o", "--out", required=True, metavar="DIR", help="output directory")
    add_overwrite(p)


def _moved(path, tmp, final):
    """``path`` under the temporary directory -> the same path under the final one."""
    if isinstance(path, str) and path.startswith(str(tmp)):
        return os.path.join(str(final), os.path.relpath(path, str(tmp)))
    return path


def run(args) -> int:
    from ..atomic import atomic_output, check_target
    from ..report import build_report
    from ..workbench import diagnose

    inputs = [args.bag, args.description]
    check_target(args.out, overwrite=args.overwrite, inputs=inputs, option="-o")  # before the work
    t0 = time.monotonic()
    plant, desc, ds, model = load_from_args(args)
    d = diagnose(ds, model, plant.candidates(desc), folds=args.folds, greedy_mode=True, quiet=args.json)
    with atomic_output(args.out, overwrite=args.overwrite, inputs=inputs, option="-o", verb="report") as tmp:
        page = build_report(ds, d, str(tmp), title=f"cablelab report: {desc.name or plant.name}",
                            warnings=getattr(args, "warnings", ()), overlay="overlay")
        write_overlay_bag(args, plant, ds, greedy_stages(ds, d.greedy), os.path.join(str(tmp), "overlay"))
    seconds = time.monotonic() - t0
    index = _moved(page.index, tmp, args.out)
    figures = [_moved(f, tmp, args.out) for f in page.figures]
    out = with_warnings(args, {"index": index, "figures": figures, "seconds": seconds,
                               "final": d.final.effects, "error": d.final.error})
    if args.json:
        print(dump_json(out))
    else:
        added = [s.added for s in d.greedy[1:]]
        print(f"missing: {', '.join(added) if added else 'no significant effect'} (held-out NRMSE "
              f"{100 * d.baseline_error:.2f} % -> {100 * d.final.error:.2f} %)")
        print(f"wrote {index} ({len(figures)} figures, {seconds:.1f} s)")
    return 0
