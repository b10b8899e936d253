"""Write a synthetic fleet of winch bags with planted drifts (cablelab.plants.axis.fleet): N
machines x D days, an independent solve_ivp simulation (tanh Coulomb + viscous friction), friction
rising on one machine and a force-sensor offset appearing on another.

Run: ./run python bench/make_fleet.py OUT [--machines 6] [--days 10] [--rate 0.02 --since 20]
Then: ./run cablelab batch OUT -o OUT_RESULTS --greedy
"""
from __future__ import annotations

import argparse
import json

from cablelab.plants.axis.fleet import Drift, default_drifts, machine_names, write_fleet


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("out", help="fleet root directory to write (<machine>/day-<DD>/)")
    ap.add_argument("--machines", type=int, default=6)
    ap.add_argument("--days", type=int, default=10)
    ap.add_argument("--rate", type=float, default=None,
                    help="friction drift per day on the second machine (default 0.05)")
    ap.add_argument("--since", type=int, default=None, help="day the friction starts to rise")
    ap.add_argument("--offset-day", type=int, default=None, help="day the sensor offset appears")
    ap.add_argument("--offset", type=float, default=0.5, help="sensor offset, N")
    ap.add_argument("--duration", type=float, default=6.0, help="bag length, s")
    args = ap.parse_args(argv)
    names = machine_names(args.machines)
    drifts = default_drifts(names, args.days)
    if args.rate is not None or args.since is not None or args.offset_day is not None:
        drifts = []
        if len(names) >= 2:
            drifts.append(Drift(names[1], "friction", since=args.since if args.since is not None
                                else int(0.4 * args.days), rate=0.05 if args.rate is None else args.rate))
        if len(names) >= 4:
            drifts.append(Drift(names[3], "offset", since=args.offset_day if args.offset_day is not None
                                else int(0.6 * args.days), value=args.offset))
    write_fleet(args.out, args.machines, args.days, drifts, duration=args.duration, progress=True)
    print(json.dumps([{"machine": d.machine, "kind": d.kind, "effect": d.effect, "param": d.param,
                       "first_changed_day": d.first_changed_day, "rate": d.rate, "value": d.value}
                      for d in drifts]))
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
