"""Options shared by the workbench verbs (compare, diagnose, identify, report)."""
from __future__ import annotations

import json
import math
from typing import Sequence

from ..errors import CablelabError
from .numeric import number


def add_bag(p) -> None:
    """The bag and its plant description (every verb that reads a recorded run)."""
    p.add_argument("bag", help="rosbag2 directory or its .mcap file")
    p.add_argument("--description", metavar="FILE",
                   help="plant description YAML (default: /plant_description in the bag)")
    add_recover(p)
    add_time_unit(p)


def add_time_unit(p) -> None:
    """``--time-unit {auto,s}``: stamps that look like milliseconds are refused unless told."""
    p.add_argument("--time-unit", choices=("auto", "s"), default="auto",
                   help="unit of the stamps: auto (refuse stamps that look like milliseconds: integer "
                        "stamps 1 apart) or s (they are seconds, e.g. a 1 Hz recording)")


def limits_from_args(args):
    """:class:`~cablelab.timebase.Limits` of the time-base checks from ``--time-unit``."""
    from ..timebase import Limits

    return Limits(time_unit=getattr(args, "time_unit", "auto") or "auto")


def add_recover(p) -> None:
    """``--recover``: every verb that reads a bag accepts an unfinished one (recorder killed)."""
    p.add_argument("--recover", action="store_true",
                   help="read an unfinished bag (recorder killed) up to its last complete chunk "
                        "(cablelab repair BAG makes it a complete bag)")


def add_overwrite(p) -> None:
    """``--overwrite``: every verb that writes refuses an existing output without it."""
    p.add_argument("--overwrite", action="store_true", help="replace an existing output")


def plant_cli_options(verb: str | None = None) -> dict:
    """The command-line options plants declare (:func:`cablelab.plant_interface.option` fields of
    their ``options_type``): flag -> ``(dest, CliOption, owners)``, ``owners`` the plants that
    declare it; only those ``verb`` offers (None: every verb's)."""
    from ..plant_interface import cli_options
    from ..registry import available_plants, get_plant

    found: dict = {}
    for name in available_plants():
        try:
            plant = get_plant(name)
        except CablelabError:
            continue
        for dest, spec in cli_options(plant.options_type):
            if verb is None or verb in spec.verbs:
                found.setdefault(spec.flag, (dest, spec, []))[2].append(name)
    return found


def add_plant_options(p, verb: str) -> None:
    """The options the plants add to ``verb`` (e.g. the CDPR's ``--tensions``), each once, its
    help naming the plants it belongs to; not given = None (the plant's default applies).

    Knowing them imports every plant, so a parser that can defer (:class:`cablelab.cli.OneLineParser`)
    adds them only when it parses: the other verbs do not pay for the import."""
    def add(parser) -> None:
        group = parser.add_argument_group("plant options")
        for flag, (dest, spec, owners) in sorted(plant_cli_options(verb).items()):
            kw = {"choices": spec.choices} if spec.choices else {"metavar": "VALUE"}
            group.add_argument(flag, dest=dest, default=None,
                               help=f"{' / '.join(owners)} only: {spec.help}", **kw)

    if hasattr(p, "defer"):
        p.defer(add)
    else:
        add(p)


def plant_option_values(args) -> dict:
    """dest -> value of every plant option given on the command line (for
    :meth:`~cablelab.plant_interface.DatasetOptions.build`)."""
    return {dest: getattr(args, dest) for dest, _, _ in plant_cli_options().values()
            if getattr(args, dest, None) is not None}


def check_plant_options(args, plant) -> None:
    """A plant-specific option given for a bag of another plant is an error (it would be
    silently ignored): one line naming the option and the plants it belongs to."""
    for flag, (dest, _, owners) in plant_cli_options().items():
        if getattr(args, dest, None) is None or plant.name in owners:
            continue
        raise CablelabError(f"{flag} {getattr(args, dest)}: an option of plant "
                            f"{' / '.join(owners)} only, and {args.bag} holds plant "
                            f"{plant.name} (leave {flag} out)")


def add_json(p) -> None:
    p.add_argument("--json", action="store_true", help="print one JSON object on stdout")


def add_common(p, verb: str, *, effects_required: bool = False) -> None:
    """The options of the workbench verbs (compare, diagnose, identify, report), with the plant
    options ``verb`` offers."""
    add_bag(p)
    p.add_argument("--effects", metavar="A,B", default="", required=effects_required,
                   help="effects added to the plant's nominal model (ids: docs/interface.md section 3)")
    p.add_argument("--baseline", metavar="A,B", default=None,
                   help="replace the plant's nominal effects ('none' = empty model)")
    p.add_argument("--fix", metavar="NAME=VALUE", action="append", default=[],
                   help="known parameter moved to the left-hand side (repeatable)")
    add_plant_options(p, verb)
    add_strict(p)
    p.add_argument("--cutoff", type=number(gt=0, unit="Hz"), metavar="HZ", default=None,
                   help="zero-phase Butterworth cut-off for positions (default fs/10)")
    p.add_argument("--decimate", type=number(ge=1, integer=True), metavar="K", default=None,
                   help="keep every K-th sample after filtering")
    add_json(p)


def add_strict(p) -> None:
    """``--strict``: refuse a fit whose data do not determine every parameter."""
    p.add_argument("--strict", action="store_true",
                   help="refuse a rank-deficient fit (default: hold the parameters the recording "
                        "does not excite at their description or neutral values, with a warning)")


def add_folds(p) -> None:
    p.add_argument("--folds", type=number(ge=0, le=1000, integer=True), default=5, metavar="K",
                   help="blocked k-fold cross-validation over time (default 5; identify: 0 = none)")


def conditioning_from_args(args):
    """:class:`~cablelab.conditioning.Conditioning` from the shared options (defaults where unset)."""
    from ..conditioning import Conditioning

    kw = {}
    cutoff = getattr(args, "cutoff", None)
    if cutoff is not None and not (math.isfinite(cutoff) and cutoff > 0):
        raise CablelabError(f"--cutoff {cutoff!r}: expected a frequency > 0 in Hz")
    decimate = getattr(args, "decimate", None)
    if decimate is not None and decimate < 1:
        raise CablelabError(f"--decimate {decimate}: expected an integer >= 1")
    folds = getattr(args, "folds", None)
    if folds is not None and (folds < 0 or folds == 1):
        raise CablelabError(f"--folds {folds}: expected 0 (none) or at least 2 folds")
    if getattr(args, "segments", None) is not None and args.segments < 1:
        raise CablelabError(f"--segments {args.segments}: expected an integer >= 1")
    if getattr(args, "cutoff", None) is not None:
        kw["cutoff_hz"] = args.cutoff
    if getattr(args, "decimate", None):
        kw["decimate"] = args.decimate
    if getattr(args, "border", None) is not None:
        kw["border"] = args.border
    return Conditioning(**kw)


def add_overlay_out(p, *, greedy: bool = False) -> None:
    """``--out BAG2`` (the model overlay bag, :mod:`cablelab.overlay`) and ``--overwrite``."""
    what = ("the nominal model and the model after each added effect (needs --greedy)" if greedy
            else "the model")
    p.add_argument("--out", metavar="BAG2",
                   help=f"also write a bag with the input's topics plus the measured channels, the "
                        f"prediction and the residual of {what} as /<plant>/model/... topics "
                        f"(for Foxglove and PlotJuggler; see docs/interface.md)")
    add_overwrite(p)


def write_overlay_out(args, plant, ds, stages) -> None:
    """Write the overlay bag of ``stages`` to ``args.out`` (if given) atomically: whole or not at
    all, never into the input (:func:`cablelab.atomic.atomic_output`); its warnings join
    ``args.warnings``."""
    if not getattr(args, "out", None):
        return
    from ..atomic import atomic_output

    with atomic_output(args.out, overwrite=args.overwrite, inputs=[args.bag, args.description]) as tmp:
        write_overlay_bag(args, plant, ds, stages, tmp)


def write_overlay_bag(args, plant, ds, stages, path) -> None:
    """The overlay bag of ``stages`` (with the plant's markers when it draws itself) at ``path``
    (a new directory); its warnings join ``args.warnings``."""
    from ..bags import open_bag
    from ..overlay import write_overlay

    bag = open_bag(args.bag, recover=getattr(args, "recover", False))
    markers = plant.markers(bag, ds.description) if plant.markers is not None else None
    warnings = write_overlay(path, bag, ds.plant, stages, markers=markers)
    args.warnings = list(getattr(args, "warnings", []) or []) + warnings


def greedy_stages(ds, steps) -> list:
    """The overlay stages of a greedy waterfall (:class:`~cablelab.diagnose.result.Step` s):
    each step's model as the diagnosis fitted it on the whole record, ``nominal`` then
    ``plus_<effect>``."""
    from ..overlay import stage_from_fit, stage_name

    return [stage_from_fit(stage_name(s.added), ds, s.fit) for s in steps]


def parse_fixed(items: Sequence[str] | None) -> dict:
    """``["M=95.1", "Fc=20"]`` -> ``{"M": 95.1, "Fc": 20.0}`` with one-line errors."""
    out = {}
    for item in items or ():
        for part in str(item).split(","):
            if not part.strip():
                continue
            if "=" not in part:
                raise CablelabError(f"--fix {part!r}: expected NAME=VALUE")
            k, v = part.split("=", 1)
            if k.strip() in out:
                raise CablelabError(f"--fix {k.strip()}: given twice ({k.strip()}={out[k.strip()]:g} and {part.strip()})")
            try:
                out[k.strip()] = float(v)
            except ValueError:
                raise CablelabError(f"--fix {part!r}: value {v!r} is not a number") from None
    return out


def load_from_args(args, *, check_out: bool = False):
    """(plant, description, dataset, model) from the shared options; the input checks' warning
    lines are kept in ``args.warnings`` (see :func:`with_warnings`). ``check_out``: check the
    ``--out`` target first (before any work: never over the input, never replaced unasked)."""
    from ..effect_spec import parse_effect_list
    from ..workbench import build_model, load_checked

    if check_out and getattr(args, "out", None):
        from ..atomic import check_target

        check_target(args.out, overwrite=args.overwrite, inputs=[args.bag, args.description])

    options = {"conditioning": conditioning_from_args(args), **plant_option_values(args)}
    plant, desc, ds, check = load_checked(args.bag, args.description, options,
                                          recover=getattr(args, "recover", False),
                                          before_dataset=lambda p: check_plant_options(args, p),
                                          limits=limits_from_args(args))
    args.warnings = list(check.warnings) + check_measured(ds)
    baseline = None
    if args.baseline is not None:
        baseline = () if args.baseline.strip() in ("", "none") else parse_effect_list(args.baseline)
    fixed = parse_fixed(args.fix)
    for name, value in fixed.items():
        if not math.isfinite(value):
            raise CablelabError(f"--fix {name}={value}: the value must be a finite number")
    model = build_model(plant, desc, parse_effect_list(args.effects), baseline, fixed,
                        strict=getattr(args, "strict", False))
    from ..model import KNOWN_OUTPUT

    if not model.effects and KNOWN_OUTPUT not in ds.signals:   # nothing known, nothing to fit
        raise CablelabError(f"--baseline {args.baseline}: the model has no effects left to fit; add some "
                            f"with --effects A,B (e.g. --effects {','.join(plant.baseline(desc))})")
    return plant, desc, ds, model


def check_measured(ds) -> list[str]:
    """Measured channels that are exactly zero in every usable sample. All of them: nothing to
    compare or fit (an effort never recorded, a dead sensor), one line naming them. Some: a
    warning line each (a channel the motion never moves, e.g. the sideways swing of a planar
    free swing, is fitted with the others)."""
    import numpy as np

    y = np.asarray(ds.y, dtype=float)
    ok = np.asarray(ds.valid, dtype=bool) & np.isfinite(y).all(axis=1)
    if not ok.any():
        return []
    zero = [ch for c, ch in enumerate(ds.channels) if not np.any(y[ok, c])]
    if len(zero) == len(ds.channels):
        raise CablelabError(f"channel {', '.join(repr(ch) for ch in zero)} is zero in all "
                            f"{int(ok.sum())} usable samples: no measurement to compare or fit (was "
                            "it recorded? check the bag's effort / tension fields)")
    return [f"channel {ch!r} is zero in all {int(ok.sum())} usable samples (not measured, or never "
            "moved by this recording)" for ch in zero]


def flag_impossible(args, effects, params: dict, units: dict | None = None, where: str = "") -> None:
    """Add a ``PHYSICALLY IMPOSSIBLE`` warning to ``args.warnings`` for every identified mass or
    inertia of the ``effects`` (ids) in ``params`` that is not > 0 (:mod:`cablelab.plausibility`)."""
    from ..plausibility import impossible_parameters, positive_parameters

    lines = impossible_parameters(params, positive_parameters(effects), units, where)
    args.warnings = list(getattr(args, "warnings", []) or []) + lines


def with_warnings(args, out: dict) -> dict:
    """``out`` with the input checks' ``"warnings"`` list (JSON); in text mode each warning is
    printed first as ``warning: ...``."""
    warnings = list(getattr(args, "warnings", []) or [])
    warnings += [w for w in out.get("warnings", ()) if w and w not in warnings]   # the verb's own (held)
    out["warnings"] = warnings
    if not getattr(args, "json", False):
        for w in warnings:
            print(f"warning: {w}")
    return out


def check_alpha(value: float, name: str = "--alpha") -> None:
    """A significance level must lie in (0, 1)."""
    if not (0.0 < value < 1.0):
        raise CablelabError(f"{name} {value!r}: expected a significance level between 0 and 1 (e.g. 0.01)")


def param_line(name: str, v: dict, tag: str = "") -> str:
    """``"           M = 95.1 +- 0.3 kg"``: one parameter of a verb's JSON (value, stderr, unit)."""
    unit = f" {v['unit']}" if "unit" in v else ""
    return f"  {name:>12} = {v['value']:.6g} +- {v['stderr']:.2g}{unit}{tag}"


def _clean(o):
    if isinstance(o, float):
        return o if math.isfinite(o) else None
    if isinstance(o, dict):
        return {str(k): _clean(v) for k, v in o.items()}
    if isinstance(o, (list, tuple)):
        return [_clean(v) for v in o]
    if hasattr(o, "item") and not isinstance(o, (str, bytes)):
        try:
            return _clean(o.item())
        except (ValueError, AttributeError):
            pass
    return o


def dump_json(obj) -> str:
    """Strict JSON (non-finite numbers as null)."""
    return json.dumps(_clean(obj), allow_nan=False)
