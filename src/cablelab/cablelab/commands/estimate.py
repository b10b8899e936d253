"""``cablelab estimate BAG [plant options] [--effects a,b] [--out BAG2] --json``.

Dispatches on the plant of the bag's description to its registered ``estimate(bag,
description, options, effects=..., out=...)`` (``options``: the
:class:`~cablelab.plant_interface.DatasetOptions` with the plant's own typed options, e.g. the
CDPR's ``--tensions`` and ``--pose``), which returns a dict or an object
with ``summary() -> dict`` (CONTRACT section 5: cdpr ``{"plant", "samples", "mass": {"mean",
"std", "max_abs_dev"}, "com": {"x", "y"}}``; crane: swing-angle statistics).
"""
from __future__ import annotations

from ..errors import CablelabError
from ._workbench_args import (add_bag, add_json, add_overwrite, add_plant_options, check_plant_options,
                              dump_json, limits_from_args, plant_option_values, with_warnings)

HELP = "estimate the payload (CDPR mass and CoM) or the swing (crane) per sample from a bag"


def add_arguments(p) -> None:
    add_bag(p)
    add_plant_options(p, "estimate")
    p.add_argument("--effects", metavar="A,B", default="",
                   help="effects added to the plant's nominal model (e.g. pulley_geometry, "
                        "platform_inertia, winch_coulomb_friction)")
    p.add_argument("--out", metavar="BAG2", help="also write the per-sample estimates as a bag")
    add_overwrite(p)
    add_json(p)


def _without_gaps(res, check):
    """Per-sample estimates (``res.t``, ``res.mass``) inside a gap of any input topic rest on
    interpolated inputs: they become NaN, so the summary counts and averages only the samples
    of the contiguous segments (the written ``--out`` bag keeps every sample)."""
    import dataclasses

    import numpy as np

    if check is None or not check.gaps or not dataclasses.is_dataclass(res) \
            or not hasattr(res, "t") or not hasattr(res, "mass"):
        return res
    keep = check.mask(np.asarray(res.t, dtype=float), 0.0)
    return dataclasses.replace(res, mass=np.where(keep, res.mass, np.nan))


def run(args) -> int:
    import contextlib
    import dataclasses

    from ..atomic import atomic_output, check_target
    from ..bagcheck import check_bag
    from ..bags import open_bag
    from ..effect_spec import parse_effect_list
    from ..plant_interface import DatasetOptions
    from ..registry import available_plants, get_plant
    from ..workbench import load_bag_description

    if args.out:   # before any work: never over the input, never over an output unasked
        check_target(args.out, overwrite=args.overwrite, inputs=[args.bag, args.description])
    bag = open_bag(args.bag, recover=args.recover)
    desc = load_bag_description(args.bag, args.description, bag)
    plant = get_plant(desc.plant)
    check_plant_options(args, plant)
    options = DatasetOptions.build(plant, plant_option_values(args))
    args.check = check_bag(bag, plant, desc, options, limits_from_args(args))
    args.warnings = args.check.warnings
    fn = plant.estimate
    if fn is None:
        able = [p for p in available_plants() if get_plant(p).estimate is not None]
        raise CablelabError(f"plant {desc.plant}: no estimator (cablelab estimate supports "
                            f"{', '.join(able)})")
    options = dataclasses.replace(options, derived_velocity=args.check.derived_velocity)
    effects = parse_effect_list(args.effects)
    writing = atomic_output(args.out, overwrite=args.overwrite, inputs=[args.bag, args.description],
                           verb="estimate") \
        if args.out else contextlib.nullcontext(None)
    with writing as tmp:   # the estimates bag appears whole under --out, or not at all
        res = fn(bag, desc, options, effects=effects, out=None if tmp is None else str(tmp))
    res = _without_gaps(res, getattr(args, "check", None))
    summary = res.summary() if hasattr(res, "summary") else dict(res)
    if isinstance(summary.get("mass"), dict):     # a mass estimate that is not > 0 is no result
        from ..plausibility import impossible_mass

        args.warnings = list(args.warnings) + impossible_mass(summary["mass"].get("mean"))
    out = with_warnings(args, summary)
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
            if k != "warnings":
                print(f"  {k}: {v}")
    if args.out:
        print(f"  estimates written to {args.out}")
    return 0
