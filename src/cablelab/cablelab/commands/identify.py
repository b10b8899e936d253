"""``cablelab identify BAG --effects a,b --json``: parameters with uncertainty and fit."""
from __future__ import annotations

from ._workbench_args import (add_common, add_folds, dump_json, flag_impossible, load_from_args,
                              param_line, with_warnings)

HELP = "identify the parameters of the nominal model + --effects, with standard errors"


def add_arguments(p) -> None:
    add_common(p, "identify")
    add_folds(p)
    p.add_argument("--simulation", choices=("nmse", "pearson"), default=None,
                   help="refine by a simulation-based (free-run) fit with this objective "
                        "(003 eq. 28 NMSE or 000 eq. 3-7 Pearson)")


def run(args) -> int:
    from ..workbench import identify_report

    _, _, ds, model = load_from_args(args)
    res = identify_report(ds, model, folds=args.folds, simulation=args.simulation, quiet=args.json)
    flag_impossible(args, model.effects, res.params)
    if res.simulation is not None:
        units = {k: v.get("unit", "") for k, v in res.params.items()}
        flag_impossible(args, model.effects, {k: v["value"] for k, v in res.simulation["params"].items()},
                        units, where="simulation-based fit")
    out = with_warnings(args, res.to_json())
    if args.json:
        print(dump_json(out))
        return 0
    f = res.quality
    held = f"held-out {100 * f.cv_nrmse:.2f} %, {f.folds} folds" if f.cv_nrmse is not None \
        else "no cross-validation"
    print(f"plant {res.plant}, model {' + '.join(res.effects)}: NRMSE {100 * f.nrmse:.2f} % "
          f"({held}), rank {f.rank}, condition {f.condition:.3g}")
    for name, v in res.params.items():
        print(param_line(name, v, " (held: not excited)" if v.get("held") else
                         " (fixed)" if v["fixed"] else ""))
    if res.simulation is not None:
        sim = res.simulation
        print(f"simulation-based fit ({sim['objective']}): NMSE {sim['nmse']:.4g}, Pearson "
              f"{sim['pearson']:.5f}, {sim['iterations']} iterations")
        for name, v in sim["params"].items():
            print(param_line(name, v))
    return 0
