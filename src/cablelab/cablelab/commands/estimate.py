"""``cablelab estimate BAG [--tensions {dynamometer,motor}] [--effects a,b] [--out BAG2] --json``.

Dispatches on the plant of the bag's description to ``cablelab.plants.<plant>.estimate_bag(bag,
description, tensions=..., effects=..., pose=..., out=...)``, which returns a dict or an object
with ``summary() -> dict`` (CONTRACT section 5: cdpr ``{"plant", "samples", "mass": {"mean",
"std", "max_abs_dev"}, "com": {"x", "y"}}``; crane: swing-angle statistics).
"""
from __future__ import annotations

import importlib
import inspect

from ..errors import CablelabError

HELP = "estimate the payload (CDPR mass and CoM) or the swing (crane) per sample from a bag"


def add_arguments(p) -> None:
    p.add_argument("bag", help="rosbag2 directory or its .mcap file")
    p.add_argument("--description", metavar="FILE",
                   help="plant description YAML (default: /plant_description in the bag)")
    p.add_argument("--tensions", choices=("dynamometer", "motor"), default="dynamometer",
                   help="CDPR: cable tensions from the dynamometers or from the motor torques")
    p.add_argument("--effects", metavar="A,B", default="",
                   help="effects added to the plant's nominal model (e.g. pulley_geometry, "
                        "platform_inertia, winch_coulomb_friction)")
    p.add_argument("--pose", choices=("desired", "measured"), default="desired",
                   help="CDPR: pose for the wrench matrix (001 uses the desired pose)")
    p.add_argument("--out", metavar="BAG2", help="also write the per-sample estimates as a bag")
    p.add_argument("--json", action="store_true", help="print one JSON object on stdout")


def run(args) -> int:
    from ..bags import open_bag
    from ..description import load_description
    from ..model import parse_effect_list
    from ._workbench_args import dump_json

    desc = load_description(args.description) if args.description else open_bag(args.bag).description
    if desc is None:
        raise CablelabError(f"{args.bag}: no /plant_description in the bag; give --description FILE")
    try:
        mod = importlib.import_module(f"cablelab.plants.{desc.plant}")
    except ModuleNotFoundError:
        mod = None
    fn = getattr(mod, "estimate_bag", None)
    if fn is None:
        raise CablelabError(f"plant {desc.plant}: no estimator (cablelab estimate supports cdpr and crane)")
    kwargs = {"tensions": args.tensions, "effects": parse_effect_list(args.effects),
              "pose": args.pose, "out": args.out}
    accepted = inspect.signature(fn).parameters
    if not any(p.kind == p.VAR_KEYWORD for p in accepted.values()):
        kwargs = {k: v for k, v in kwargs.items() if k in accepted}
    res = fn(args.bag, desc, **kwargs)
    out = res.summary() if hasattr(res, "summary") else dict(res)
    if args.json:
        print(dump_json(out))
        return 0
    if "mass" in out:
        m = out["mass"]
        print(f"{out['plant']}: {out['samples']} samples, model {' + '.join(out.get('effects', []))}")
        print(f"  mass  {m['mean']:.2f} kg  (std {m['std']:.2f}, max |dev| {m['max_abs_dev']:.2f})")
        print(f"  CoM   x_G {1000 * out['com']['x']:.1f} mm, y_G {1000 * out['com']['y']:.1f} mm")
        if "truth" in out:
            print(f"  truth {out['truth']['mass']:.2f} kg: error {out['truth']['mass_error_percent']:+.2f} %")
    else:
        for k, v in out.items():
            print(f"  {k}: {v}")
    if args.out:
        print(f"  estimates written to {args.out}")
    return 0
