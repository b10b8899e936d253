"""``cablelab import FILE --plant P --map SPEC [--description YAML] -o BAG``.

Turns a CSV (header row of column names) or MATLAB .mat time series into a contract bag with the
plant's joint-state topic and ``/plant_description``. SPEC maps contract fields to columns with an
optional scale: ``time=t,position=qm,effort=35.15*vir`` (factors joined by ``*`` or ``/``; a
factor is a number, a column, or a scalar variable of the file such as ``gtau``). Single-joint
plants use ``time, position, velocity, effort``; multi-joint plants ``position.<joint>`` etc.
"""
from __future__ import annotations

import io
import os
import re

import numpy as np

from ..errors import CablelabError

HELP = "import a CSV or MAT time series into a contract bag (with /plant_description)"

FIELDS = ("position", "velocity", "effort")


def add_arguments(p) -> None:
    p.add_argument("file", help="CSV (header row) or MATLAB .mat file")
    from ..registry import available_plants

    p.add_argument("--plant", required=True, choices=available_plants())
    p.add_argument("--map", required=True, metavar="SPEC",
                   help="e.g. time=t,position=qm,effort=35.15*vir (multi-joint: position.slew=...)")
    p.add_argument("--description", metavar="YAML",
                   help="plant description file or YAML text (required for the workbench)")
    p.add_argument("-o", "--out", required=True, metavar="BAG", help="bag directory to write")
    p.add_argument("--overwrite", action="store_true", help="replace an existing output")
    p.add_argument("--json", action="store_true", help="print one JSON object")
    from ._workbench_args import add_time_unit

    add_time_unit(p)


def read_table(path: str) -> dict[str, np.ndarray]:
    """Variables of a .mat file or columns of a CSV with a header row, as float arrays."""
    if not os.path.exists(path):
        raise CablelabError(f"{path}: file not found")
    if path.lower().endswith(".mat"):
        import scipy.io

        try:
            raw = scipy.io.loadmat(path)
        except Exception as exc:  # scipy raises several types for a bad file
            raise CablelabError(f"{path}: cannot read MAT file ({exc})") from None
        out = {}
        for k, v in raw.items():
            if k.startswith("__"):
                continue
            try:
                out[k] = np.asarray(v, dtype=float).reshape(-1)
            except (TypeError, ValueError):
                continue
        return out
    try:
        with open(path, encoding="utf-8") as fh:
            content = fh.read()
    except (OSError, UnicodeDecodeError) as exc:
        raise CablelabError(f"{path}: cannot read CSV ({str(exc).splitlines()[0] if str(exc) else exc})") from None
    header = content.split("\n", 1)[0]
    delim = ";" if header.count(";") > header.count(",") else ","
    names = [h.strip().strip('"') for h in header.strip().split(delim)]
    _check_header(path, names)
    _check_cell_sizes(path, names, content, delim)
    try:
        data = np.genfromtxt(io.StringIO(content), delimiter=delim, skip_header=1, dtype=float, ndmin=2)
    except ValueError as exc:
        raise CablelabError(f"{path}: cannot read CSV ({str(exc).splitlines()[0] if str(exc) else exc})") from None
    if data.shape[1] != len(names):
        raise CablelabError(f"{path}: header has {len(names)} names but rows have {data.shape[1]} values")
    if not np.isfinite(data).all():         # which cells are text: only when some did not parse
        text = np.genfromtxt(io.StringIO(content), delimiter=delim, skip_header=1, dtype=f"U{MAX_CELL}",
                             ndmin=2, autostrip=True, comments=None)
        _check_text_cells(path, names, data, text)
    return {n: data[:, i] for i, n in enumerate(names)}


#: longest cell read (characters): a number never needs more; a longer cell is an error, not memory
MAX_CELL = 100


def _check_header(path, names) -> None:
    """Column names must be unique and non-empty: a duplicated one would silently shadow the other."""
    seen: dict[str, int] = {}
    for i, n in enumerate(names):
        if not n:
            raise CablelabError(f"{path}: row 1, column {i + 1}: empty column name in the header")
        if n in seen:
            raise CablelabError(f"{path}: row 1: column name {n!r} appears twice (columns {seen[n] + 1} "
                                f"and {i + 1}): rename one")
        seen[n] = i


def _check_cell_sizes(path, names, content: str, delim: str) -> None:
    """No cell longer than :data:`MAX_CELL` characters (one huge cell would make the text table of
    every cell that wide): one line naming row and column."""
    lines = content.splitlines()
    lengths = np.fromiter(map(len, lines), dtype=np.int64, count=len(lines))
    if lengths.size == 0 or lengths.max() <= MAX_CELL:
        return
    for r in np.flatnonzero(lengths > MAX_CELL):
        cells = lines[r].split(delim)
        sizes = [len(c.strip()) for c in cells]
        c = int(np.argmax(sizes))
        if sizes[c] > MAX_CELL:
            col = repr(names[c]) if c < len(names) else str(c + 1)
            raise CablelabError(f"{path}: row {int(r) + 1}, column {col}: a cell of {sizes[c]} characters "
                                f"(at most {MAX_CELL}) is not a number")


_MISSING = {"", "nan", "NaN", "NAN", "na", "NA", "n/a", "N/A"}


def _check_text_cells(path, names, data, text) -> None:
    """A cell that is neither a number nor empty/NaN is an error naming row, column and value
    (genfromtxt would silently turn it into NaN)."""
    if text.shape != data.shape:
        return
    nan = ~np.isfinite(data)
    if not nan.any():
        return
    strip = np.char.strip(np.char.strip(text), '"')
    bad = nan & ~np.isin(strip, list(_MISSING)) & ~np.isin(np.char.lower(strip), ["inf", "-inf", "+inf"])
    if bad.any():
        r, c = np.argwhere(bad)[0]
        raise CablelabError(f"{path}: row {int(r) + 2}, column {names[c]!r}: {str(text[r, c])!r} is not a number "
                            f"({int(bad.sum())} such cell(s))")


def parse_spec(spec: str) -> dict[str, list[tuple[str, str]]]:
    """``"time=t,effort=35.15*vir"`` -> ``{"time": [("*", "t")], "effort": [("*", "35.15"), ("*", "vir")]}``."""
    out = {}
    for part in spec.split(","):
        if not part.strip():
            continue
        if "=" not in part:
            raise CablelabError(f"--map {part!r}: expected FIELD=EXPRESSION (e.g. effort=35.15*vir)")
        field, expr = (s.strip() for s in part.split("=", 1))
        tokens = re.split(r"([*/])", expr.replace(" ", ""))
        factors = [("*", tokens[0])] + [(tokens[i], tokens[i + 1]) for i in range(1, len(tokens) - 1, 2)]
        if any(not f for _, f in factors):
            raise CablelabError(f"--map {part!r}: empty factor in {expr!r}")
        out[field] = factors
    return out


def evaluate(field: str, factors, table: dict[str, np.ndarray], source: str) -> np.ndarray:
    """Product/quotient of numbers, scalar variables and exactly one column."""
    value: np.ndarray | float = 1.0
    series = 0
    for op, name in factors:
        try:
            x: np.ndarray | float = float(name)
        except ValueError:
            if name not in table:
                raise CablelabError(f"{source}: --map {field}: no column {name!r} (have: "
                                    f"{', '.join(sorted(table))})") from None
            x = table[name]
            if x.size == 1:
                x = float(x[0])
            else:
                series += 1
        _check_factor(field, op, name, x, source)
        value = value * x if op == "*" else value / x
    if series != 1:
        raise CablelabError(f"{source}: --map {field}: expected exactly one column in the expression, "
                            f"found {series}")
    return np.asarray(value, dtype=float)


def _check_factor(field: str, op: str, name: str, x, source: str) -> None:
    """A scale factor must be finite and non-zero, a divisor column must hold no zero: the
    imported values would be inf, NaN or all 0."""
    if np.ndim(x) == 0:
        if not np.isfinite(x) or x == 0:
            role = "divisor" if op == "/" else "scale factor"
            raise CablelabError(f"--map {field}: {role} {name!r} = {float(x):g}; expected a finite, "
                                f"non-zero number")
    elif op == "/" and np.any(np.asarray(x) == 0):
        k = int(np.flatnonzero(np.asarray(x) == 0)[0])
        raise CablelabError(f"{source}: --map {field}: divisor column {name!r} is 0 in "
                            f"{int(np.sum(np.asarray(x) == 0))} row(s) (first: data row {k + 1}); the "
                            f"imported values would be infinite")


def joint_topic(plant: str, desc=None) -> tuple[str, tuple[str, ...]]:
    """The plant's joint-state topic and joint names (its :class:`~cablelab.registry.Plant`); for
    a plant whose joints depend on the description (``Plant.joints`` None), the joint-state topic
    its ``topic_names(desc)`` gives first (the description may remap it) and its names."""
    from ..registry import get_plant

    p = get_plant(plant)
    topic, joints = p.joint_topic, p.joints
    if not joints and desc is not None and p.topic_names is not None:
        named = p.topic_names(desc) or {}
        if named:
            topic = topic if topic in named else next(iter(named))
            joints = named[topic]
    if not topic or not joints:
        raise CablelabError(f"import --plant {plant}: the plant declares no fixed joint-state topic "
                            "to import into")
    return topic, tuple(joints)


def import_series(path: str, plant: str, spec: str, desc=None) -> dict:
    """Read ``path`` and evaluate ``spec`` into ``{"t", "names", "position", "velocity", "effort"}``
    arrays (N, k) (None for an unmapped field)."""
    table = read_table(path)
    fields = parse_spec(spec)
    topic, joints = joint_topic(plant, desc)
    if "time" not in fields:
        raise CablelabError("--map: missing 'time=' (e.g. time=t)")
    fields_time = fields.pop("time")
    t = evaluate("time", fields_time, table, path)
    n = t.size
    arrays = {f: None for f in FIELDS}
    for key, factors in fields.items():
        base, _, joint = key.partition(".")
        if base not in FIELDS:
            raise CablelabError(f"--map {key}: unknown field (allowed: time, {', '.join(FIELDS)})")
        if not joint:
            if len(joints) != 1:
                raise CablelabError(f"--map {key}: plant {plant} has joints {', '.join(joints)}; "
                                    f"write {base}.<joint>")
            joint = joints[0]
        if joint not in joints:
            raise CablelabError(f"--map {key}: unknown joint {joint!r} (plant {plant}: {', '.join(joints)})")
        v = evaluate(key, factors, table, path)
        if v.size != n:
            raise CablelabError(f"{path}: --map {key} has {v.size} samples, time has {n}")
        if arrays[base] is None:
            arrays[base] = np.full((n, len(joints)), np.nan)
        arrays[base][:, joints.index(joint)] = v
    if arrays["position"] is None and arrays["effort"] is None:
        raise CablelabError("--map: map at least position and effort")
    if np.any(t < 0):
        k = int(np.flatnonzero(t < 0)[0])
        col = next((name for _, name in fields_time if name in table), "time")
        raise CablelabError(f"{path}: row {k + 2}, column {col!r}: time {float(t[k]):g} s is negative "
                            f"({int((t < 0).sum())} such rows); bag stamps start at 0 or later: "
                            "shift the time column")
    if not np.all(np.isfinite(t)):
        raise CablelabError(f"{path}: time column has {int((~np.isfinite(t)).sum())} missing or non-finite values")
    if not np.all(np.diff(t) > 0):
        k = int(np.flatnonzero(np.diff(t) <= 0)[0])
        raise CablelabError(f"{path}: time column is not strictly increasing (row {k + 3}: {float(t[k + 1])!r} after "
                            f"{float(t[k])!r})")
    return {"topic": topic, "t": t, "names": list(joints), **arrays}


def run(args) -> int:
    from ..atomic import atomic_output, check_target
    from ..bags import BagWriter
    from ..description import load_description
    from ._workbench_args import dump_json, limits_from_args

    if not args.description:
        raise CablelabError(f"import --plant {args.plant}: give --description FILE or YAML text "
                            f"(e.g. \"{{plant: axis, axis: {{joint_type: prismatic}}}}\")")
    desc = load_description(args.description)
    if desc.plant != args.plant:
        raise CablelabError(f"--description is for plant {desc.plant}, not --plant {args.plant}")
    inputs = [args.file] + ([args.description] if os.path.exists(args.description) else [])
    check_target(args.out, overwrite=args.overwrite, inputs=inputs, option="-o")
    s = import_series(args.file, args.plant, args.map, desc)
    from ..timebase import check_stamps, raise_if_impossible

    tb = check_stamps(s["t"], topic=f"{args.file}: time column", limits=limits_from_args(args))
    raise_if_impossible(tb)                 # stamps in ms: refuse with the --map fix
    with atomic_output(args.out, overwrite=args.overwrite, inputs=inputs, option="-o", verb="import") as tmp:
        with BagWriter(tmp) as w:
            w.write_description(desc.to_yaml(), t=float(s["t"][0]))
            w.write_joint_states(s["topic"], s["t"], s["names"], s["position"], s["velocity"], s["effort"])
    nan = {}
    for f in FIELDS:
        if s[f] is not None:
            mapped = s[f][:, np.isfinite(s[f]).any(axis=0)]    # joints this --map fills
            nan[f] = int((~np.isfinite(mapped)).any(axis=1).sum())
    warnings = [f"{args.file}: {n} of {s['t'].size} samples have no finite {f} value (missing cells)"
                for f, n in nan.items() if n]
    warnings += tb.warnings()               # gaps, irregular rate
    info = {"bag": args.out, "plant": args.plant, "topic": s["topic"], "samples": int(s["t"].size),
            "duration": float(s["t"][-1] - s["t"][0]), "warnings": warnings}
    if not args.json:
        for w in warnings:
            print(f"warning: {w}")
    if args.json:
        print(dump_json(info))
    else:
        print(f"wrote {args.out}: {info['samples']} {s['topic']} messages over {info['duration']:.3f} s")
    return 0
