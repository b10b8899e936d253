"""Validation of numeric input in files: plant descriptions (YAML 1.2 numbers, duplicated keys,
encoding, a pulley radius the geometry cannot hold, the public field validators) and CSV import
(huge cells, negative times, duplicated headers): one line naming file, key or row and column."""
from __future__ import annotations

import math
import os

import numpy as np
import pytest
import yaml
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from robust_helpers import CDPR

EXAMPLES = int(os.environ.get("CABLELAB_FUZZ_EXAMPLES", "80"))
FUZZ = settings(max_examples=EXAMPLES, deadline=None, derandomize=not os.environ.get("CABLELAB_FUZZ_RANDOM"),
                suppress_health_check=list(HealthCheck))
AXIS = "plant: axis\naxis:\n  joint_type: prismatic\n  inertia: {}\n"


# ----------------------------------------------------------------------------- descriptions

@pytest.mark.parametrize("text, value", [("2e3", 2000.0), ("2E3", 2000.0), ("1.5e-3", 0.0015), (".5", 0.5),
                                         ("+3", 3.0), ("2", 2.0), ("2.0e+2", 200.0), ("010", 10.0)])
def test_yaml_12_numbers(text, value):
    from cablelab.description import load_description

    assert load_description(AXIS.format(text)).axis.inertia == value


@pytest.mark.parametrize("text, words", [
    ("yes", ["axis.inertia", "expected a number, got 'yes'"]),      # YAML 1.1 would read true
    ("1:30", ["axis.inertia", "'1:30'"]),                           # YAML 1.1 would read 90
    ("1_000", ["axis.inertia", "'1_000'"]),
    ("2e3x", ["axis.inertia", "'2e3x'", "e.g. 2000.0 or 2e3"]),
    (".nan", ["axis.inertia", "finite"]),
    ("-2", ["axis.inertia", "positive"]),
])
def test_not_numbers_are_one_line(text, words):
    from cablelab.description import load_description
    from cablelab.errors import CablelabError

    with pytest.raises(CablelabError) as exc:
        load_description(AXIS.format(text))
    msg = str(exc.value)
    assert "\n" not in msg and all(w in msg for w in words), msg


def test_duplicated_key_names_key_and_lines(tmp_path):
    from cablelab.description import load_description
    from cablelab.errors import CablelabError

    f = tmp_path / "d.yaml"
    f.write_text("plant: axis\naxis:\n  joint_type: prismatic\n  inertia: 2\n  inertia: 3\n")
    with pytest.raises(CablelabError) as exc:
        load_description(f)
    assert str(exc.value) == f"{f}: line 5: duplicated key 'inertia' (first given on line 4)"


def test_non_utf8_description_is_one_line(tmp_path, cli):
    f = tmp_path / "d.yaml"
    f.write_bytes(b"plant: axis\naxis: {joint_type: prismatic}\nname: \xe9t\xe9\n")
    res = cli("compare", CDPR, "--description", f)
    assert res.code == 2 and len(res.err_lines) == 1, res.err
    assert str(f) in res.err and "not a UTF-8 text file (byte 0xe9" in res.err


def test_pulley_radius_larger_than_the_geometry(tmp_path, cli):
    """r_p = 100 m leaves no tangent from any sheave to its attachment: one line naming the key
    and the largest radius these poses allow (the poses' own bound, checked here: a radius just
    below it is accepted by the same check)."""
    from cablelab.bags import open_bag
    from cablelab.errors import CablelabError
    from cablelab.plants.cdpr.geometry import check_pulley_radius

    doc = yaml.safe_load(open_bag(CDPR).description_yaml)
    doc["cdpr"]["pulley_radius"] = 100
    f = tmp_path / "d.yaml"
    f.write_text(yaml.safe_dump(doc))
    for verb in ("compare", "estimate"):
        res = cli(verb, CDPR, "--description", f)
        assert res.code == 2 and len(res.err_lines) == 1, res.err
        assert "cdpr.pulley_radius: 100 m is larger than the geometry allows" in res.err
    c = doc["cdpr"]["cables"]
    A = np.array([x["exit_point"] for x in c])
    B = np.array([x["anchor_point"] for x in c])
    pos = np.array([[0.0, 0.0, 1.0]])
    d = (pos[:, None, :] + B) - A                                   # level platform, z swivel axes
    h, dz = np.hypot(d[..., 0], d[..., 1]), d[..., 2]
    largest = float(np.min((h * h + dz * dz) / (2 * h)))            # |O B| = r for r = this
    check_pulley_radius(A, B, pos, None, 0.999 * largest)
    with pytest.raises(CablelabError):
        check_pulley_radius(A, B, pos, None, 1.001 * largest)


def test_field_validators_name_the_key_path():
    from cablelab import fields
    from cablelab.errors import CablelabError

    obj = {"a": 2, "v": [1, 2], "c": "x", "t": "2e3"}
    assert fields.number(obj, "a", "p", positive=True) == 2.0 and isinstance(fields.number(obj, "a", "p"), float)
    assert fields.number(obj, "missing", "p", default=1.5) == 1.5
    cases = [(lambda: fields.vector(obj, "v", "p.q"), "p.q.v: expected 3 numbers, got 2"),
             (lambda: fields.number(obj, "a", "p", le=1), "p.a: expected a number <= 1, got 2"),
             (lambda: fields.number(obj, "t", "p"), "p.t: expected a number, got '2e3'"),
             (lambda: fields.choice(obj, "c", "p", ("y", "z")), "p.c: expected one of 'y', 'z', got 'x'"),
             (lambda: fields.check_keys(obj, "p", ("a",), ("v",)), "p.c: unknown key (allowed: a, v)"),
             (lambda: fields.mapping([1], "p"), "p: expected a mapping, got list")]
    for fn, msg in cases:
        with pytest.raises(CablelabError) as exc:
            fn()
        assert str(exc.value).startswith(msg), str(exc.value)


def _spellings(x: float) -> st.SearchStrategy:
    """YAML spellings of the number x: YAML 1.1 ones (with a dot) and YAML 1.2-only ones."""
    out = [repr(float(x)), f"{x:.17e}", f"{x:.17E}", f"{x:.17g}"]
    if x == int(x) and abs(x) < 1e15:
        out += [str(int(x)), f"{int(x)}.0", f"{int(x):+d}"]
    mant, exp = f"{x:.17e}".split("e")
    out.append(f"{mant.rstrip('0').rstrip('.')}e{int(exp)}")        # 2e3: YAML 1.1 reads it as text
    return st.sampled_from(out)


@FUZZ
@given(x=st.one_of(st.floats(1e-12, 1e12), st.integers(1, 10 ** 9).map(float)), data=st.data())
def test_random_description_numbers(x, data):
    """Hypothesis: every YAML 1.1 or 1.2 spelling of a positive number is read as that number;
    its negative is refused with one line naming the key (inertia must be > 0)."""
    from cablelab.description import load_description
    from cablelab.errors import CablelabError

    text = data.draw(_spellings(x))
    got = load_description(AXIS.format(text)).axis.inertia
    assert got == pytest.approx(float(text), rel=1e-15) and math.isclose(got, x, rel_tol=1e-12)
    neg = text[1:] if text.startswith("+") else text
    with pytest.raises(CablelabError) as exc:
        load_description(AXIS.format("-" + neg))
    assert "axis.inertia" in str(exc.value) and "\n" not in str(exc.value)


# ----------------------------------------------------------------------------- CSV import

def _csv(path, header="t,q,u", rows=None):
    t = np.arange(300) * 0.01
    rows = rows if rows is not None else [f"{float(a)!r},{float(np.sin(a))!r},{float(np.cos(a))!r}" for a in t]
    path.write_text("\n".join([header] + rows) + "\n")
    return path


def _import(cli, src, out):
    return cli("import", src, "--plant", "axis", "--map", "time=t,position=q,effort=u",
               "--description", "{plant: axis, axis: {joint_type: prismatic}}", "-o", out)


def test_csv_huge_cell_is_one_line(cli, tmp_path):
    rows = [f"{a * 0.01!r},1.0,2.0" for a in range(300)]
    rows[7] = "0.07," + "9" * 10_000_000 + ",2.0"
    res = _import(cli, _csv(tmp_path / "big.csv", rows=rows), tmp_path / "out")
    assert res.code == 2 and len(res.err_lines) == 1, res.err
    assert "big.csv: row 9, column 'q': a cell of 10000000 characters" in res.err
    assert not (tmp_path / "out").exists()


def test_csv_negative_times_are_one_line(cli, tmp_path):
    rows = [f"{a * 0.01 - 1.0!r},1.0,2.0" for a in range(300)]
    res = _import(cli, _csv(tmp_path / "neg.csv", rows=rows), tmp_path / "out")
    assert res.code == 2 and len(res.err_lines) == 1, res.err
    assert "neg.csv: row 2, column 't': time -1 s is negative (100 such rows)" in res.err


def test_csv_duplicated_header_is_one_line(cli, tmp_path):
    res = _import(cli, _csv(tmp_path / "dup.csv", header="t,q,q"), tmp_path / "out")
    assert res.code == 2 and len(res.err_lines) == 1, res.err
    assert "dup.csv: row 1: column name 'q' appears twice (columns 2 and 3)" in res.err


def test_csv_valid_import_still_works(cli, tmp_path):
    from cablelab.bags import open_bag

    res = _import(cli, _csv(tmp_path / "ok.csv"), tmp_path / "out")
    assert res.code == 0, res.err
    js = open_bag(tmp_path / "out").joint_state("/axis/joint_states")
    assert js.t.size == 300 and np.allclose(js.position[:, 0], np.sin(np.arange(300) * 0.01))
