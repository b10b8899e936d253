"""``cablelab diagnose BAG [--effects a,b] [--greedy] --json``: which effect is missing."""
from __future__ import annotations

from ._workbench_args import (add_common, add_folds, check_alpha, dump_json, flag_impossible,
                              load_from_args, with_warnings)

HELP = "rank the missing physical effects by held-out error (blocked k-fold), --greedy adds them"


def add_arguments(p) -> None:
    add_common(p)
    add_folds(p)
    p.add_argument("--candidates", metavar="A,B", default=None,
                   help="effects to try (default: every effect applicable to the plant)")
    p.add_argument("--greedy", action="store_true",
                   help="add the best significant effect until none helps (the waterfall)")
    p.add_argument("--alpha", type=float, default=0.01, help="family-wise significance level")
    p.add_argument("--min-gain", type=float, default=0.05,
                   help="minimum relative held-out error reduction of a significant effect, over the "
                        "channels it changes (default 0.05)")


def run(args) -> int:
    from ..model import parse_effect_list
    from ..workbench import diagnose

    check_alpha(args.alpha)
    if not args.min_gain >= 0:
        from ..errors import CablelabError

        raise CablelabError(f"--min-gain {args.min_gain!r}: expected a relative gain >= 0 (e.g. 0.05)")
    plant, desc, ds, model = load_from_args(args)
    cands = parse_effect_list(args.candidates) if args.candidates else plant.candidates(desc)
    out = diagnose(ds, model, cands, folds=args.folds, alpha=args.alpha, min_gain=args.min_gain,
                   greedy_mode=args.greedy, quiet=args.json)
    for c in out.ranking:
        flag_impossible(args, (c.effect,), c.params, c.extra.get("units"),
                        where=f"candidate {c.effect}")
    for step in out.greedy:
        flag_impossible(args, step.effects, step.params, step.units,
                        where=f"model {' + '.join(step.effects)}")
    doc = with_warnings(args, out.to_json())
    if args.json:
        print(dump_json(doc))
        return 0
    print("\n".join(out.lines()))
    return 0
