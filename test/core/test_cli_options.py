"""Hostile command-line options, each a one-line error naming the option and value
(exit 2, nothing on stdout), and the advice in messages names flags the verb really has."""
from __future__ import annotations

import pytest

from robust_helpers import EMPS


@pytest.mark.parametrize("argv, words", [
    (["compare", EMPS, "--baseline", "none"], ["--baseline none", "--effects"]),
    (["diagnose", EMPS, "--baseline", "none", "--json"], ["--baseline none"]),
    (["diagnose", EMPS, "--alpha", "2"], ["argument --alpha", "'2'", "(0, 1)"]),
    (["diagnose", EMPS, "--alpha", "nan"], ["argument --alpha", "'nan'"]),
    (["diagnose", EMPS, "--min-gain", "-1"], ["argument --min-gain", "'-1'"]),
    (["compare", EMPS, "--cutoff", "0"], ["argument --cutoff", "'0'", "> 0 [Hz]"]),
    (["compare", EMPS, "--cutoff", "5000"], ["--cutoff", "fs/2"]),
    (["compare", EMPS, "--decimate", "0"], ["argument --decimate", "'0'", "integer >= 1"]),
    (["identify", EMPS, "--folds", "1"], ["--folds 1"]),
    (["compare", EMPS, "--segments", "0"], ["argument --segments", "'0'"]),
    (["compare", EMPS, "--fix", "M=nan"], ["--fix M=nan", "finite"]),
    (["replay", EMPS, "--rate", "nan"], ["argument --rate", "'nan'"]),
    (["replay", EMPS, "--rate", "-2"], ["argument --rate", "'-2'"]),
    (["replay", EMPS, "--topics", "/nope"], ["--topics /nope", "/axis/joint_states"]),
    (["replay", EMPS, "--start-delay", "inf"], ["argument --start-delay", "'inf'"]),
    (["record", "-o", "x", "--plant", "axis", "--duration", "-1"], ["argument --duration", "'-1'"]),
    (["record", "-o", "x", "--plant", "axis", "--flush-period", "0"], ["argument --flush-period", "'0'"]),
    (["compare", EMPS, "--cutoff", "1e-9"], ["--cutoff 1e-09 Hz", "one cycle over the"]),
    (["compare", EMPS, "--cutoff", "abc"], ["argument --cutoff", "'abc'"]),
    (["compare", EMPS, "--segments", "2.5"], ["argument --segments", "integer"]),
    (["identify", EMPS, "--fix", "M=1,M=2"], ["--fix M: given twice"]),
    (["batch", EMPS, "-o", "out", "--workers", "0"], ["argument --workers", "'0'"]),
    (["batch", EMPS, "-o", "out", "--alpha", "1"], ["argument --alpha", "'1'"]),
    (["compare", EMPS, "--frob"], ["unrecognized arguments: --frob", "cablelab --help"]),
    (["compare"], ["cablelab compare: error: the following arguments are required: bag"]),
])
def test_bad_option_is_one_line(cli, tmp_path, monkeypatch, argv, words):
    monkeypatch.chdir(tmp_path)
    res = cli(*argv)
    assert res.code == 2 and res.out == "", (res.code, res.out, res.err)
    assert len(res.err_lines) == 1 and "Traceback" not in res.err, res.err
    for w in words:
        assert w in res.err, (w, res.err)
    assert list(tmp_path.iterdir()) == []          # record wrote nothing


@pytest.mark.parametrize("verb", ["estimate", "compare", "diagnose", "identify", "report", "replay", "info"])
def test_every_bag_verb_has_the_flags_its_messages_advise(cli, verb):
    text = cli(verb, "--help").out
    for flag in ("--recover", "--description"):
        if flag == "--description" and verb in ("replay", "info"):
            continue
        assert flag in text, (verb, flag)


@pytest.mark.parametrize("verb, flags", [("estimate", ("--tensions", "--pose")),
                                         ("compare", ("--tensions",)), ("diagnose", ("--tensions",)),
                                         ("identify", ("--tensions",)), ("report", ("--tensions",)),
                                         ("excite", ("--tensions",))])
def test_help_lists_the_options_plants_add(cli, verb, flags):
    """The plants' own options (declared in their packages, added when the verb parses) are in
    the verb's --help, with the plant they belong to and their choices."""
    text = cli(verb, "--help").out
    assert "plant options" in text
    for flag in flags:
        assert flag in text, (verb, flag)
    assert "cdpr only" in text and "dynamometer,motor,both" in text
    if "--pose" not in flags:
        assert "--pose" not in text                # the CDPR offers --pose to estimate only


def test_a_plant_option_value_outside_its_choices_is_a_usage_error(cli):
    res = cli("estimate", EMPS, "--pose", "sideways")
    assert res.code == 2 and len(res.err_lines) == 1
    assert "--pose" in res.err and "sideways" in res.err
