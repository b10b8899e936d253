"""Numeric command-line input of every verb: one parser (``cablelab.commands.numeric.number``)
checks type and range of every numeric option; the hostile cases that used to trace back are one
line, or work and give the right answer."""
from __future__ import annotations

import json
import math
import os

import numpy as np
import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from robust_helpers import EMPS, axis_bag

EXAMPLES = int(os.environ.get("CABLELAB_FUZZ_EXAMPLES", "60"))
FUZZ = settings(max_examples=EXAMPLES, deadline=None, derandomize=not os.environ.get("CABLELAB_FUZZ_RANDOM"),
                suppress_health_check=list(HealthCheck))


def _one_line_error(res, *words):
    assert res.code == 2 and "Traceback" not in res.err, res.err
    assert len(res.err_lines) == 1, res.err
    for w in words:
        assert w in res.err, (w, res.err)


# ----------------------------------------------------------------------------- the cases

@pytest.fixture(scope="module")
def short_bag(tmp_path_factory):
    """The EMPS recording cut to its first 120 samples."""
    return axis_bag(tmp_path_factory.mktemp("short") / "bag", keep=lambda t: np.arange(t.size) < 120)


@pytest.fixture(scope="module")
def zero_effort_bag(tmp_path_factory):
    return axis_bag(tmp_path_factory.mktemp("zero") / "bag", effort=lambda e: 0.0 * e)


@pytest.mark.parametrize("verb", ["compare", "diagnose", "identify"])
def test_120_samples_is_one_line(cli, short_bag, verb):
    res = cli(verb, short_bag)
    _one_line_error(res)
    assert "samples" in res.err or "record" in res.err, res.err


def test_regimes_of_a_record_shorter_than_the_reversal_window():
    """The reversal labels have one entry per sample however short the record (they used to take
    the window's length and break the residual-by-regime table): a sample is near a reversal
    iff a sign change lies within the window (+-0.05 s) of it."""
    from cablelab.dataset import Dataset
    from cablelab.diagnose.localise import REVERSAL_WINDOW_S, derived_regimes

    dt = 0.005
    t = np.arange(12) * dt                                # 12 samples < the 21-sample window
    v = np.where(np.arange(12) < 3, 1.0, -1.0)[:, None]   # one reversal between samples 2 and 3
    ds = Dataset(plant="axis", t=t, y=np.ones((12, 1)), channels=("joint",), units=("N",),
                 act_vel=v, actuators=("joint",))
    reg = derived_regimes(ds)
    assert all(len(labels) == 12 for labels in reg.values())
    half = round(REVERSAL_WINDOW_S / dt)
    expect = np.abs(np.arange(12) - 3) <= half
    assert np.array_equal(reg["reversal"] == "near reversal", expect)
    t = np.arange(40) * dt                                # and a record longer than it
    v = np.where(np.arange(40) < 30, 1.0, -1.0)[:, None]
    ds = Dataset(plant="axis", t=t, y=np.ones((40, 1)), channels=("joint",), units=("N",),
                 act_vel=v, actuators=("joint",))
    assert np.array_equal(derived_regimes(ds)["reversal"] == "near reversal", np.abs(np.arange(40) - 30) <= half)


@pytest.mark.parametrize("verb", ["compare", "report", "identify", "diagnose"])
def test_all_zero_effort_is_one_line(cli, zero_effort_bag, tmp_path, verb):
    extra = ["-o", tmp_path / "rep"] if verb == "report" else []
    res = cli(verb, zero_effort_bag, *extra)
    _one_line_error(res, "channel 'joint' is zero in all")
    assert not (tmp_path / "rep").exists()


def test_fix_every_parameter_gives_the_fit_it_fixes(cli):
    """``--fix M=..,Fv=..`` (every parameter of the model fixed, comma-separated) is a model with
    nothing left to fit; fixed at the least-squares optimum it must reproduce that fit's error."""
    free = json.loads(cli("compare", EMPS, "--json").out)
    params = {k: v["value"] for k, v in free["params"].items()}
    assert set(params) == {"M", "Fv"}
    fix = ",".join(f"{k}={v!r}" for k, v in params.items())
    res = cli("compare", EMPS, "--fix", fix, "--json")
    assert res.code == 0, res.err
    fixed = json.loads(res.out)
    assert fixed["channels"]["joint"]["nrmse"] == pytest.approx(free["channels"]["joint"]["nrmse"], rel=1e-6)
    worse = json.loads(cli("compare", EMPS, "--fix", "M=2,Fv=1", "--json").out)
    assert worse["channels"]["joint"]["nrmse"] > 5 * free["channels"]["joint"]["nrmse"]
    res = cli("identify", EMPS, "--fix", "M=2", "--fix", "Fv=1", "--json")
    assert res.code == 0 and json.loads(res.out)["params"]["M"]["value"] == 2.0, res.err


def test_cutoff_below_one_cycle_per_record(cli):
    res = cli("compare", EMPS, "--cutoff", "1e-9")
    _one_line_error(res, "--cutoff 1e-09 Hz", "one cycle over the")


# ----------------------------------------------------------------------------- every numeric option

#: (verb, option) -> validity of a value (an oracle written from the options' meaning)
FINITE = math.isfinite
RULES = {
    ("compare", "--cutoff"): lambda x: FINITE(x) and x > 0,
    ("compare", "--decimate"): lambda x: FINITE(x) and x == int(x) and x >= 1,
    ("compare", "--segments"): lambda x: FINITE(x) and x == int(x) and 1 <= x <= 1000,
    ("diagnose", "--folds"): lambda x: FINITE(x) and x == int(x) and 0 <= x <= 1000,
    ("diagnose", "--alpha"): lambda x: FINITE(x) and 0 < x < 1,
    ("diagnose", "--min-gain"): lambda x: FINITE(x) and 0 <= x <= 1,
    ("batch", "--workers"): lambda x: FINITE(x) and x == int(x) and 1 <= x <= 4096,
    ("batch", "--alpha"): lambda x: FINITE(x) and 0 < x < 1,
    ("replay", "--rate"): lambda x: FINITE(x) and x > 0,
    ("replay", "--start-delay"): lambda x: FINITE(x) and 0 <= x <= 3600,
    ("record", "--duration"): lambda x: FINITE(x) and x >= 0,
    ("record", "--flush-period"): lambda x: FINITE(x) and 0 < x <= 3600,
    ("excite", "--duration"): lambda x: FINITE(x) and 5 <= x <= 3600,
    ("excite", "--seed"): lambda x: FINITE(x) and x == int(x) and 0 <= x <= 2 ** 32 - 1,
}


def _numeric_options():
    """(verb, option, parser) of every option whose type is the shared numeric parser."""
    from cablelab.cli import build_parser

    parser = build_parser()
    sub = next(a for a in parser._actions if a.__class__.__name__ == "_SubParsersAction")
    out = []
    for verb, p in sub.choices.items():
        for a in p._actions:
            if getattr(a.type, "__name__", "") in ("number", "integer") and a.option_strings:
                out.append((verb, a.option_strings[-1], p))
    return out


def test_every_numeric_option_uses_the_shared_parser():
    from cablelab.cli import build_parser

    opts = {(v, o) for v, o, _ in _numeric_options()}
    covered = {(v, o) for v, o in opts if (v, o) in RULES or any(o == ro for _, ro in RULES)}
    assert covered == opts
    assert {("compare", "--cutoff"), ("batch", "--workers"), ("record", "--flush-period")} <= opts
    parser = build_parser()
    sub = next(a for a in parser._actions if a.__class__.__name__ == "_SubParsersAction")
    for verb, p in sub.choices.items():                  # no numeric option left on a bare float/int
        for a in p._actions:
            assert a.type not in (float, int), (verb, a.option_strings)


NUMBER_TEXT = st.one_of(
    st.floats(allow_nan=True, allow_infinity=True).map(repr),
    st.integers(-10 ** 6, 10 ** 6).map(str),
    st.floats(-1e4, 1e4).map(lambda x: f"{x:e}"),                # 1.5e+03 spellings
    st.sampled_from(["0", "1", "1.0", "2.5", "-1", "1e-9", "1e9", "inf", "nan", "abc", "", " 3 ", "1_0",
                     "0x10", "5.", ".5"]))


@FUZZ
@given(data=st.data())
def test_random_numeric_options(data):
    """Hypothesis: a random value for every numeric option of every verb is parsed to the number
    it spells when the option's rule allows it, and refused with one line naming the option and
    the value otherwise (parsing only: no verb runs)."""
    import contextlib
    import io

    for verb, opt, parser in _numeric_options():
        text = data.draw(NUMBER_TEXT, label=f"{verb} {opt}")
        rule = RULES.get((verb, opt)) or next(r for (_, o), r in RULES.items() if o == opt)
        try:
            x = float(text.strip()) if "_" not in text else math.nan
        except ValueError:
            x = math.nan
        err = io.StringIO()
        positional = ["x", "-o", "y"] if verb in ("batch", "report") else ["-o", "y", "--plant", "axis"] if verb == "record" \
            else ["x", "--params", "a", "-o", "y"] if verb == "excite" else ["x"]
        with contextlib.redirect_stderr(err):
            try:
                args = parser.parse_args(positional + [f"{opt}={text}"])
                code = 0
            except SystemExit as exc:
                code = exc.code
        if rule(x):
            assert code == 0, (verb, opt, text, err.getvalue())
            assert getattr(args, opt.lstrip("-").replace("-", "_")) == x
        else:
            lines = [ln for ln in err.getvalue().splitlines() if ln.strip()]
            assert code == 2 and len(lines) == 1, (verb, opt, text, err.getvalue())
            assert f"argument {opt}" in lines[0] and repr(text) in lines[0], lines
