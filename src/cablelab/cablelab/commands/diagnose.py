"""``cablelab diagnose BAG [--effects a,b] [--greedy] --json``: which effect is missing."""
from __future__ import annotations

from .numeric import number
from ._workbench_args import (add_common, add_folds, add_overlay_out, check_alpha, dump_json,
                              flag_impossible, greedy_stages, load_from_args, with_warnings,
                              write_overlay_out)

HELP = "rank the missing physical effects by held-out error (blocked k-fold), --greedy adds them"


def add_arguments(p) -> None:
    add_common(p, "diagnose")
    add_folds(p)
    p.add_argument("--candidates", metavar="A,B", default=None,
                   help="effects to try (default: every effect applicable to the plant)")
    p.add_argument("--greedy", action="store_true",
                   help="add the best significant effect until none helps (the waterfall)")
    p.add_argument("--alpha", type=number(gt=0, lt=1), default=0.01, help="family-wise significance level")
    p.add_argument("--min-gain", type=number(ge=0, le=1), default=0.05,
                   help="minimum relative held-out error reduction of a significant effect, over the "
                        "channels it changes (default 0.05)")
    add_overlay_out(p, greedy=True)


def run(args) -> int:
    from ..errors import CablelabError
    from ..effect_spec import parse_effect_list
    from ..workbench import diagnose

    check_alpha(args.alpha)
    if not args.min_gain >= 0:
        raise CablelabError(f"--min-gain {args.min_gain!r}: expected a relative gain >= 0 (e.g. 0.05)")
    if args.out and not args.greedy:
        raise CablelabError("--out: the overlay bag holds the greedy waterfall's models; add --greedy")
    plant, desc, ds, model = load_from_args(args, check_out=True)
    cands = parse_effect_list(args.candidates) if args.candidates else plant.candidates(desc)
    out = diagnose(ds, model, cands, folds=args.folds, alpha=args.alpha, min_gain=args.min_gain,
                   greedy_mode=args.greedy, quiet=args.json)
    for c in out.ranking:
        flag_impossible(args, (c.effect,), c.params, c.units,
                        where=f"candidate {c.effect}")
    for step in out.greedy:
        flag_impossible(args, step.effects, step.params, step.units,
                        where=f"model {' + '.join(step.effects) or 'nominal'}")
    if args.out:
        write_overlay_out(args, plant, ds, greedy_stages(ds, out.greedy))
    from ..excite import excite_commands

    doc = with_warnings(args, out.to_json())
    doc["excite"] = excite_commands(out.ranking, out.plant, args.bag, tuple(out.held))
    if args.json:
        print(dump_json(doc))
        return 0
    print("\n".join(out.lines() + doc["excite"]))
    if args.out:
        print(f"model overlay (measured, prediction, residual per stage) written to {args.out}")
    return 0
