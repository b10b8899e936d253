"""``cablelab repair BAG [-o OUT]``: rewrite a killed recording as a complete bag."""
from __future__ import annotations

from ._workbench_args import add_json, add_overwrite, add_recover, dump_json

HELP = "rewrite an unfinished recording (recorder killed) as a complete bag (metadata, index)"


def add_arguments(p) -> None:
    p.add_argument("bag", help="rosbag2 directory or its .mcap file (finished or not)")
    p.add_argument("-o", "--out", metavar="BAG2", default=None,
                   help="bag directory to write (default: BAG_repaired next to BAG)")
    add_overwrite(p)
    add_recover(p)   # accepted for uniformity: repair always reads up to the last complete chunk
    add_json(p)


def run(args) -> int:
    from ..bags.repair import repair_bag

    info = repair_bag(args.bag, args.out, overwrite=args.overwrite)
    if args.json:
        print(dump_json(info))
    else:
        for w in info["warnings"]:
            print(f"warning: {w}")
        state = "damaged or incomplete: only its intact part was saved" if info["warnings"] else \
            "unfinished" if info["recovered"] else "complete"
        print(f"wrote {info['bag']}: {info['messages']} messages on {len(info['topics'])} topics over "
              f"{info['duration']:.3f} s (input was {state})")
    return 0
