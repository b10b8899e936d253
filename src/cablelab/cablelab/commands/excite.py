"""``cablelab excite (BAG | --description FILE) --params a,b [--duration S] -o REF [--json]``:
design a reference trajectory that makes the named parameters identifiable and separable."""
from __future__ import annotations

import math

from ._workbench_args import (add_overwrite, add_plant_options, add_recover, check_plant_options, dump_json,
                              plant_option_values)
from .numeric import number

HELP = "design a reference trajectory (within the machine's limits) that separates named parameters"
DESCRIPTION = (
    "Design an excitation: a finite Fourier series per joint (Swevers et al.) whose coefficients "
    "minimise the condition number of the regressor of the model holding the named parameters, "
    "scaled into the machine's joint ranges, speeds and accelerations (a delay tau of time_delay "
    "is designable through its linearised column: the change of the fit's residual with tau, minus the "
    "time derivative of the model's output with the parameters fitted on BAG where the delay leaves the "
    "outputs alone; the design also maximises that column against BAG's noise and reports the smallest "
    "delay the run shows: the delay whose held-out gain reaches diagnose's threshold); written as a bag of the "
    "plant's reference topic that the plant's controller node plays "
    "(pd_feedforward --plant P --ros-args -p reference_bag:=REF).")


def add_arguments(p) -> None:
    p.add_argument("bag", nargs="?", default=None,
                   help="the recording that confounds the parameters (its condition number is "
                        "condition_before); optional with --description")
    p.add_argument("--description", metavar="FILE",
                   help="plant description YAML (default: /plant_description in the bag)")
    add_recover(p)
    add_plant_options(p, "excite")
    p.add_argument("--params", metavar="A,B", required=True,
                   help="parameters to separate, as the fit names them (e.g. 'OF[hoist],m'; 'tau,I_tot' "
                        "for a delay, linearised)")
    p.add_argument("--duration", type=number(ge=5, le=3600, unit="s"), default=60.0, metavar="S",
                   help="length of the designed reference, s (default 60; for a plant whose machine "
                        "starts away from the design's centre, the CDPR, it includes the move from there)")
    p.add_argument("--seed", type=number(ge=0, le=2**32 - 1, integer=True), default=0, help="seed of the optimiser's random start")
    p.add_argument("-o", "--out", required=True, metavar="REF", help="reference bag to write")
    add_overwrite(p)
    p.add_argument("--json", action="store_true", help="print one JSON object on stdout")


def run(args) -> int:
    from ..atomic import atomic_output, check_target
    from ..errors import CablelabError
    from ..excite import design, get_exciter, write_reference
    from ..effect_spec import parse_effect_list
    from ..workbench import load_bag_description, load_checked

    if not (math.isfinite(args.duration) and args.duration > 0):
        raise CablelabError(f"--duration {args.duration!r}: expected a length in seconds > 0")
    if args.bag is None and not args.description:
        raise CablelabError("give the recording (BAG) or --description FILE")
    inputs = [x for x in (args.bag, args.description) if x]
    check_target(args.out, overwrite=args.overwrite, inputs=inputs, option="-o")
    before = None
    if args.bag is not None:
        plant, desc, before, _ = load_checked(args.bag, args.description, plant_option_values(args),
                                              recover=args.recover,
                                              before_dataset=lambda p: check_plant_options(args, p))
    else:
        desc = load_bag_description(None, args.description)
    params = parse_effect_list(args.params)
    d = design(desc.plant, desc, params, duration=args.duration, before_ds=before, seed=args.seed)
    with atomic_output(args.out, overwrite=args.overwrite, inputs=inputs, option="-o") as tmp:
        write_reference(tmp, d, get_exciter(desc.plant), getattr(desc, "yaml_text", None),
                        overwrite=True)
    out = d.to_json()
    out["reference"] = str(args.out)
    if args.json:
        print(dump_json(out))
        return 0
    before_txt = "-" if d.condition_before is None else f"{d.condition_before:.4g}"
    print(f"wrote {args.out}: {d.t[-1]:.0f} s of {', '.join(d.limits.joints)} for "
          f"{', '.join(params)}; condition number {before_txt} -> {d.condition_after:.4g} "
          f"(model {' + '.join(d.model.effects)}, {d.seconds:.1f} s)")
    if d.detectable is not None:
        det = d.detectable
        print(f"smallest delay this run shows: {1e3 * det['tau']:.3g} ms (diagnose's {100 * det['min_gain']:g} % "
              f"held-out gain: {1e3 * det['by_gain']:.3g} ms, its likelihood-ratio test: "
              f"{1e3 * det['by_test']:.3g} ms; at the noise of {args.bag}'s fit); a shorter delay "
              f"is not told from none")
    elif "tau" in params:
        print("smallest delay this run shows: unknown without the noise; give the recording (BAG)")
    print(f"play it: pd_feedforward --plant {desc.plant} --ros-args -p reference_bag:={args.out}")
    return 0
