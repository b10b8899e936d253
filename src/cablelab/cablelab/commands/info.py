"""``cablelab info BAG``: topics, types, message counts, the plant description of a bag and the
samples ``cablelab record`` counted as lost (metadata.yaml ``custom_data``)."""
from __future__ import annotations

import json

from ._workbench_args import add_recover

HELP = "show a bag's topics, message counts, duration and plant description"


def add_arguments(p) -> None:
    p.add_argument("bag", help="rosbag2 directory or its .mcap file")
    p.add_argument("--json", action="store_true", help="print one JSON object")
    add_recover(p)


def run(args) -> int:
    from ..bags import bag_info

    info = bag_info(args.bag, recover=args.recover)
    if args.json:
        print(json.dumps(info))
    else:
        print(f"bag:      {info['path']}\nduration: {info['duration']:.3f} s\nmessages: {info['messages']}")
        for t in info["topics"]:
            print(f"  {t['name']:<40} {t['type']:<40} {t['count']:>9}")
        if info.get("recovered"):
            print("note:     unfinished bag, read up to its last complete chunk")
        for w in info.get("warnings", []):
            print(f"warning:  {w}")
        for m in info.get("contract_mismatches", []):
            print(f"warning:  {m['topic']} has type {m['type']}, the contract says {m['contract_type']}")
        if info.get("plant"):
            print(f"plant:    {info['plant']}")
        lost = info.get("lost")
        if lost is not None:
            bad = {t: n for t, n in lost.items() if n}
            if bad:
                for t, n in sorted(bad.items()):
                    print(f"warning:  the recorder lost {n} samples of {t}")
            else:
                print(f"lost:     0 samples (recorder checked {len(lost)} topics)")
    return 0
