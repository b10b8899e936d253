"""Property-based fuzz suite of the command line (hypothesis, bounded examples): hostile bags
(random bytes, truncated, empty), hostile recordings (NaN/inf blocks, stamps out of order,
gaps, duplicates, unknown joint names, empty topic), descriptions with wrong types, CSV with
text cells, unknown names and out-of-range numbers for every option. Every case ends in exit 0
with strict JSON, or exit 2 with exactly one stderr line naming the file, topic, key or value;
never a traceback, never a partial output, the input untouched. ``bench/fuzz_long.py`` runs the
same properties with many more examples (CABLELAB_FUZZ_EXAMPLES)."""
from __future__ import annotations

import json
import math
import os
import re
import tempfile
from pathlib import Path

import numpy as np
import pytest
import yaml
from hypothesis import HealthCheck, assume, given, settings
from hypothesis import strategies as st

from robust_helpers import tree_snapshot

EXAMPLES = int(os.environ.get("CABLELAB_FUZZ_EXAMPLES", "12"))
FUZZ = settings(max_examples=EXAMPLES, deadline=None, derandomize=not os.environ.get("CABLELAB_FUZZ_RANDOM"),
                suppress_health_check=[HealthCheck.function_scoped_fixture, HealthCheck.too_slow,
                                       HealthCheck.data_too_large])
DESC = "plant: axis\nname: fuzz slide\naxis:\n  joint_type: prismatic\n  inertia: 2.0\n"
READ_VERBS = ("compare", "diagnose", "identify", "estimate", "info", "report", "replay", "repair")


@pytest.fixture(scope="module")
def clean():
    """A small clean axis run (10 s at 200 Hz, closed-form simulator) as arrays."""
    from cablelab.description import load_description
    from cablelab.plants.axis.sim import AxisTruth
    from cablelab.plants.axis.truth import simulate_axis

    run = simulate_axis(load_description(DESC), AxisTruth(inertia=2.0, viscous=5.0, coulomb=1.0),
                        duration=10.0, fs=200.0, amplitude=0.3, noise_effort=0.05, seed=3)
    return run.t, run.q, run.effort


def _write_bag(path, t, q, effort, names=("joint",), desc=DESC, log=None):
    from cablelab.bags import BagWriter

    with BagWriter(path) as w:
        if desc is not None:
            w.write_description(desc)
        kw = {} if log is None else {"log_time": log}
        w.write_joint_states("/axis/joint_states", t, list(names), q.reshape(len(t), -1)[:, :len(names)],
                             None, effort.reshape(len(t), -1)[:, :len(names)], **kw)
    return Path(path)


def check_outcome(res, *, must_name=(), outputs=(), inputs=()):
    """The contract of every case (see the module docstring). Returns the parsed JSON or None."""
    assert "Traceback" not in res.err, res.err
    assert res.code in (0, 2), (res.code, res.err)
    if res.code == 2:
        assert len(res.err_lines) == 1, res.err
        assert re.match(r"^cablelab( [a-z]+)?: error: \S", res.err), res.err
        if must_name:
            assert any(str(n) in res.err for n in must_name), (must_name, res.err)
        for o in outputs:
            assert not Path(o).exists(), f"partial output {o} left after an error"
        return None
    for o in outputs:
        p = Path(o)
        if p.exists():
            assert not any(".partial-" in q.name for q in p.parent.iterdir())
    text = res.out.strip()
    if text.startswith("{"):
        return json.loads(text, parse_constant=lambda c: pytest.fail(f"non-strict JSON {c}"))
    return None


# ----------------------------------------------------------------------------- hostile files
@FUZZ
@given(kind=st.sampled_from(["random", "truncated", "empty", "dir_random", "empty_dir", "missing"]),
       blob=st.binary(min_size=0, max_size=2048), cut=st.floats(0.0, 0.98), verb=st.sampled_from(READ_VERBS),
       recover=st.booleans())
def test_hostile_bag_files(cli, clean, kind, blob, cut, verb, recover):
    with tempfile.TemporaryDirectory() as d:
        d = Path(d)
        if kind == "random":
            target = d / "x.mcap"
            target.write_bytes(blob)
        elif kind == "truncated":
            src = _write_bag(d / "good", *clean)
            mcap = src / "good.mcap"
            data = mcap.read_bytes()
            mcap.write_bytes(data[:int(cut * len(data))])
            (src / "metadata.yaml").unlink()
            target = src
        elif kind == "empty":
            target = d / "e.mcap"
            target.write_bytes(b"")
        elif kind == "dir_random":
            target = d / "bag"
            target.mkdir()
            (target / "metadata.yaml").write_bytes(blob)
            (target / "bag.mcap").write_bytes(blob[::-1])
        elif kind == "empty_dir":
            target = d / "bag"
            target.mkdir()
        else:
            target = d / "nope"
        before = tree_snapshot(target) if target.exists() else None
        out = d / "out"
        args = [verb, target] + (["--recover"] if recover else [])
        if verb in ("report", "repair"):
            args += ["-o", out]
        if verb == "replay":
            args += ["--rate", "1e9", "--start-delay", "0"]
        if verb in ("compare", "diagnose", "identify", "report"):
            args += ["--folds", "2"] if verb != "compare" else []
        if kind == "truncated" and recover and verb in ("replay",):
            assume(False)          # a readable recovered bag would start ROS: covered by test_repair
        res = cli(*args)
        if kind != "truncated" or not recover:
            assert res.code == 2, (res.code, res.err)
        check_outcome(res, must_name=[target, target.name], outputs=[out] if res.code else [])
        if before is not None:
            assert tree_snapshot(target) == before


# ----------------------------------------------------------------------------- hostile recordings
MUTATIONS = st.lists(st.tuples(
    st.sampled_from(["nan_block", "inf", "swap", "gap", "dup", "reverse", "jump_back", "jump_fwd",
                     "names", "drop_all", "const"]),
    st.floats(0.0, 1.0), st.integers(1, 400)), min_size=1, max_size=3)


def _mutate(t, q, e, muts):
    t, q, e = t.copy(), q.copy().reshape(-1), e.copy().reshape(-1)
    names = ("joint",)
    log = t.copy()
    keep = np.ones(t.size, bool)
    for kind, where, n in muts:
        i = int(where * (t.size - 1))
        j = min(t.size, i + n)
        if kind == "nan_block":
            q[i:j] = np.nan
        elif kind == "inf":
            e[i:j] = np.inf
        elif kind == "swap" and j - i >= 2:
            t[[i, j - 1]] = t[[j - 1, i]]
        elif kind == "gap":
            keep[i:j] = False
        elif kind == "dup" and i > 0:
            t[i:j] = t[i - 1]
        elif kind == "reverse":
            t[i:j] = t[i:j][::-1].copy()
        elif kind == "jump_back":
            t[i:] -= n * 1e-3
        elif kind == "jump_fwd":
            t[i:] += n * 1e-2
        elif kind == "names":
            names = ("spindle",)
        elif kind == "drop_all":
            keep[:] = False
            keep[:min(n, t.size) // 40] = True
        elif kind == "const":
            q[:] = 0.0
    return t[keep], q[keep], e[keep], names, log[keep]


@FUZZ
@given(muts=MUTATIONS, verb=st.sampled_from(["compare", "identify", "diagnose"]))
def test_hostile_recordings(cli, clean, muts, verb):
    t, q, e, names, log = _mutate(*clean, muts)
    with tempfile.TemporaryDirectory() as d:
        if t.size == 0:
            assume(False)
        bag = _write_bag(Path(d) / "bag", t, q, e, names=names, log=log)
        before = tree_snapshot(bag)
        args = [verb, bag, "--json"] + (["--folds", "0"] if verb == "identify" else []) + \
            (["--folds", "2", "--candidates", "joint_coulomb_friction"] if verb == "diagnose" else [])
        res = cli(*args)
        out = check_outcome(res, must_name=[bag, "rank-deficient"])
        dt = np.diff(t[np.isfinite(t)])
        if np.any(dt < 0):
            assert res.code == 2 and "back in time" in res.err, res.err     # never a silent result
        if out is not None:
            assert isinstance(out["warnings"], list)
            med = np.median(dt[dt > 0]) if np.any(dt > 0) else 0
            if med and np.any(dt > 5 * med):
                assert any("gap" in w or "clock jump" in w for w in out["warnings"]), out["warnings"]
            if not (np.isfinite(q).all() and np.isfinite(e).all()):
                assert any("NaN/inf" in w for w in out["warnings"]), out["warnings"]
        assert tree_snapshot(bag) == before


# ----------------------------------------------------------------------------- descriptions
BAD_VALUES = st.one_of(st.text(max_size=8), st.lists(st.integers(), max_size=3), st.none(),
                       st.floats(allow_nan=True, allow_infinity=True), st.integers(-5, 5),
                       st.dictionaries(st.text(max_size=3), st.integers(), max_size=2))


@FUZZ
@given(key=st.sampled_from(["plant", "axis", "axis.joint_type", "axis.inertia", "gravity", "name",
                            "axis.gravity_moment", "extra", "axis.extra"]),
       value=BAD_VALUES, raw=st.one_of(st.none(), st.text(max_size=40)))
def test_hostile_descriptions(cli, clean, key, value, raw):
    with tempfile.TemporaryDirectory() as d:
        bag = _write_bag(Path(d) / "bag", *clean)
        doc = yaml.safe_load(DESC)
        node, *rest = key.split(".")
        if rest:
            doc.setdefault(node, {})
            if isinstance(doc[node], dict):
                doc[node][rest[0]] = value
        else:
            doc[node] = value
        path = Path(d) / "desc.yaml"
        path.write_text(raw if raw is not None else yaml.safe_dump(doc))
        res = cli("compare", bag, "--description", path, "--json")
        check_outcome(res, must_name=[path, key.split(".")[-1], "description", "plant", "axis"])


# ----------------------------------------------------------------------------- CSV import
@FUZZ
@given(cells=st.lists(st.tuples(st.integers(0, 59), st.integers(0, 2),
                                st.one_of(st.text(max_size=6), st.sampled_from(["", "nan", "1e400", "-", "1,2"]))),
                      max_size=4),
       header=st.sampled_from(["t,q,f", "t;q;f", "t,q", "t,q,f,g", "", "t,t,f"]),
       spec=st.sampled_from(["time=t,position=q,effort=f", "time=t,position=q,effort=2*f/x", "time=q",
                             "time=t,position.joint=q,effort=0.5*f", "time=t,speed=q", "t=t", ""]))
def test_hostile_csv_import(cli, cells, header, spec):
    rows = [[f"{0.005 * i:.3f}", f"{np.sin(0.1 * i):.5f}", f"{np.cos(0.1 * i):.5f}"] for i in range(60)]
    for r, c, v in cells:
        rows[r][c] = v
    with tempfile.TemporaryDirectory() as d:
        src = Path(d) / "in.csv"
        sep = ";" if ";" in header else ","
        src.write_text(header + "\n" + "\n".join(sep.join(r) for r in rows) + "\n")
        before = tree_snapshot(src)
        out = Path(d) / "out"
        res = cli("import", src, "--plant", "axis", "--map", spec, "--description", DESC, "-o", out, "--json")
        check_outcome(res, must_name=[src, "--map", "row", "column"], outputs=[out])
        if res.code == 0:
            from cablelab.bags import open_bag

            assert open_bag(out).counts["/axis/joint_states"] == 60          # whole, or nothing
            # a text cell never becomes a silent NaN: every non-empty non-number cell is an error
            texts = [v for _, c, v in cells if v.strip() not in ("", "nan") and not _is_number(v)]
            assert not texts or sep == ";" or header != "t,q,f", texts
        assert tree_snapshot(src) == before


def _is_number(v: str) -> bool:
    try:
        float(v)
        return True
    except ValueError:
        return False


# ----------------------------------------------------------------------------- options
NUMBERS = st.one_of(st.floats(allow_nan=True, allow_infinity=True), st.integers(-10, 10))


@FUZZ
@given(opt=st.sampled_from(["--alpha", "--min-gain", "--cutoff", "--folds", "--decimate", "--segments",
                            "--effects", "--baseline", "--fix", "--candidates", "--tensions"]),
       value=st.one_of(NUMBERS.map(str), st.text(min_size=1, max_size=12).filter(lambda s: not s.startswith("-")),
                       st.sampled_from(["none", "", "axis_inertia", "M=nan", "M=", "=3", "nope",
                                        "time_delay,time_delay", "cdpr_gravity"])),
       verb=st.sampled_from(["compare", "identify", "diagnose"]))
def test_hostile_workbench_options(cli, clean, opt, value, verb):
    if opt in ("--alpha", "--min-gain", "--candidates") and verb != "diagnose":
        verb = "diagnose"
    if opt == "--segments":
        verb = "compare"
    with tempfile.TemporaryDirectory() as d:
        bag = _write_bag(Path(d) / "bag", *clean)
        extra = [] if opt == "--folds" else (["--folds", "2"] if verb == "diagnose" else
                                             ["--folds", "0"] if verb == "identify" else [])
        if verb == "diagnose" and opt != "--candidates":
            extra += ["--candidates", "joint_coulomb_friction"]
        res = cli(verb, bag, f"{opt}={value}", "--json", *extra)
        check_outcome(res, must_name=[opt, value, value.split("=")[0], bag, "effect", "parameter",
                                      "rank-deficient"])
        if opt == "--alpha" and res.code == 0:
            assert 0 < float(value) < 1
        if opt == "--baseline" and value.strip() in ("none", ""):
            assert res.code == 2                            # an empty model has nothing to fit


@FUZZ
@given(opt=st.sampled_from(["--rate", "--start-delay", "--topics", "--duration", "--flush-period"]),
       value=st.one_of(NUMBERS.map(str), st.text(min_size=1, max_size=10).filter(lambda s: not s.startswith("-")),
                       st.sampled_from(["/nope", "/axis/joint_states,/nope", "nan", "-1", "inf", "0"])))
def test_hostile_record_replay_options(cli, clean, opt, value):
    """Only invalid values are run (a valid one would start ROS): each is one line naming it."""
    try:
        x = float(value)
    except ValueError:
        x = None
    valid = {"--rate": x is not None and math.isfinite(x) and x > 0,
             "--start-delay": x is not None and math.isfinite(x) and x >= 0,
             "--duration": x is not None and math.isfinite(x) and x >= 0,
             "--flush-period": x is not None and math.isfinite(x) and x > 0,
             "--topics": value == "/axis/joint_states"}[opt]
    assume(not valid)
    with tempfile.TemporaryDirectory() as d:
        bag = _write_bag(Path(d) / "bag", *clean)
        out = Path(d) / "rec"
        if opt in ("--rate", "--start-delay") or (opt == "--topics" and value.startswith("/")):
            res = cli("replay", bag, f"{opt}={value}")
        else:
            res = cli("record", "-o", out, "--plant", "axis", f"{opt}={value}")
        check_outcome(res, must_name=[opt, value, "topic"], outputs=[out])
        assert res.code == 2
