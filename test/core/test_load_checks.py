"""Every verb loads data through workbench.load_checked: a gap is split into segments (never
interpolated across), a clock that jumps back, reversed stamps, stamps in ms and a description
that does not match the bag are one-line errors, NaN samples and negative tensions are warnings
in the text and the JSON. Oracle: the fit of the complete EMPS recording (001-style real data)."""
from __future__ import annotations

import html
import json

import numpy as np
import pytest
import yaml

from robust_helpers import CDPR, EMPS, axis_bag, copy_bag, tree_snapshot


def _json(res):
    assert res.code == 0, res.err
    return json.loads(res.out)


@pytest.fixture(scope="module")
def full_fit():
    from cablelab.cli import main  # noqa: F401 (imports the verbs)
    from cablelab.workbench import build_model, compare, load

    plant, desc, ds = load(EMPS)
    out = compare(ds, build_model(plant, desc))
    return out.params["M"]["value"], out.samples, ds


def test_gap_is_masked_not_interpolated(cli, tmp_path, full_fit):
    """3 s of the 24.8 s EMPS recording missing: the verb reports the gap, fits the two
    segments only and finds the inertia of the complete recording (the old interpolation across
    the gap gave a different inertia: checked below as the control)."""
    M_full, n_full, ds_full = full_fit
    mid = 12.42
    bag = axis_bag(tmp_path / "gap", keep=lambda t: ~((t > mid) & (t < mid + 3.0)))
    out = _json(cli("compare", bag, "--json"))
    assert len(out["warnings"]) == 1 and "1 recording gap" in out["warnings"][0]
    assert "3 s" in out["warnings"][0] and "2 contiguous segments" in out["warnings"][0]
    M = out["params"]["M"]["value"]
    assert abs(M - M_full) < 0.01 * M_full, (M, M_full)
    # the sample count is what was fitted: the complete record's fitted samples less those in the
    # 3 s gap and its 2 x 50 border samples (the zero-speed samples are not fitted in either)
    t0 = ds_full.t[0]
    lost = ds_full.valid & (ds_full.t - t0 > mid - 0.05) & (ds_full.t - t0 < mid + 3.05)
    assert abs(out["samples"] - (n_full - lost.sum())) <= 25   # (zero-speed cut at the borders)
    # control: the same data interpolated across the gap (no mask) is measurably wrong
    from cablelab.bags import open_bag
    from cablelab.plant_interface import DatasetOptions
    from cablelab.plants import get_plant
    from cablelab.workbench import build_model, compare

    b = open_bag(bag)
    plant = get_plant("axis")
    ds = plant.dataset(b, b.description, DatasetOptions())
    M_interp = compare(ds, build_model(plant, b.description)).params["M"]["value"]
    assert abs(M_interp - M_full) > 5 * abs(M - M_full)
    # text output: the warning line is printed too
    txt = cli("compare", bag)
    assert txt.code == 0 and txt.out.startswith("warning: /axis/joint_states: 1 recording gap")


def test_clock_jump_forward_is_reported_as_clock_jump(cli, tmp_path):
    def stamps(t):
        t[t > 12.42] += 2.0            # header clock jumps 2 s ahead, log time keeps running
        return t
    bag = axis_bag(tmp_path / "jump", stamps=stamps, log=lambda t: t)
    out = _json(cli("identify", bag, "--json", "--folds", "0"))
    assert any("1 clock jump" in w for w in out["warnings"]), out["warnings"]


@pytest.mark.parametrize("case, expect", [
    ("jump_back", "go back in time 1 time(s)"),
    ("reversed", "go back in time 99 time(s)"),
    ("milliseconds", "look like milliseconds"),
])
@pytest.mark.parametrize("verb", ["compare", "diagnose", "identify"])
def test_impossible_stamps_are_one_line_errors(cli, tmp_path, case, expect, verb):
    def stamps(t):
        if case == "jump_back":
            t[t > 12.42] -= 0.5
        elif case == "reversed":
            i = np.searchsorted(t, 12.42)
            t[i:i + 100] = t[i:i + 100][::-1].copy()
        else:
            t = t * 1000.0
        return t
    bag = axis_bag(tmp_path / case, stamps=stamps, log=lambda t: t)
    before = tree_snapshot(bag)
    res = cli(verb, bag, "--json")
    assert res.code == 2 and res.out == ""
    assert len(res.err_lines) == 1 and expect in res.err and "/axis/joint_states" in res.err
    assert str(bag) in res.err
    assert tree_snapshot(bag) == before


def test_nan_samples_are_counted(cli, tmp_path):
    def eff(e):
        e[1000:1037] = np.nan
        return e
    bag = axis_bag(tmp_path / "nan", effort=eff)
    out = _json(cli("compare", bag, "--json"))
    assert any("37 of 24841 samples have NaN/inf" in w for w in out["warnings"]), out["warnings"]


def _cdpr_desc(tmp_path, n):
    from cablelab.bags import open_bag

    d = yaml.safe_load(open_bag(CDPR).description_yaml)
    d["cdpr"]["cables"] = d["cdpr"]["cables"][:n]
    p = tmp_path / f"cdpr_{n}.yaml"
    p.write_text(yaml.safe_dump(d))
    return p


@pytest.mark.parametrize("verb", ["compare", "estimate"])
def test_cdpr_description_with_5_cables_on_8_cable_bag(cli, tmp_path, verb):
    res = cli(verb, CDPR, "--description", _cdpr_desc(tmp_path, 5), "--json")
    assert res.code == 2 and res.out == "" and len(res.err_lines) == 1, res.err
    assert "has 8 winches" in res.err or "has 8 cables" in res.err
    assert "description has 5 cables" in res.err


def test_negative_tensions_are_a_loud_warning(cli, tmp_path):
    def edit(bag, w):
        ts = bag.joint_state("/cdpr/cable_tensions")
        eff = ts.effort.copy()
        eff[100:140, 2] = -25.0
        w.write_joint_states("/cdpr/cable_tensions", ts.t, ts.names, None, None, eff)
    bag = copy_bag(CDPR, tmp_path / "neg", skip={"/cdpr/cable_tensions"}, edit=edit)
    for verb in ("compare", "estimate"):
        out = _json(cli(verb, bag, "--json"))
        assert any("cable_3 has 40 of" in w and "negative tension" in w for w in out["warnings"]), out
    clean = _json(cli("estimate", CDPR, "--json"))
    assert clean["warnings"] == []


def test_crane_joint_names_must_match(cli, tmp_path):
    from cablelab.bags import open_bag

    src = open_bag(CDPR.parent / "crane_control")

    def edit(bag, w):
        js = bag.joint_state("/crane/joint_states")
        w.write_joint_states("/crane/joint_states", js.t, ["slew", "luff", "rope"], js.position,
                             js.velocity, js.effort)
    bag = copy_bag(src.path, tmp_path / "crane", skip={"/crane/joint_states"}, edit=edit)
    res = cli("compare", bag, "--json")
    assert res.code == 2 and len(res.err_lines) == 1 and "missing hoist" in res.err, res.err


def test_cdpr_estimate_excludes_samples_inside_a_pose_gap(cli, tmp_path):
    """2 s of /cdpr/reference missing: the tensions are still there, but the per-sample mass in
    the gap would rest on an interpolated pose; it is reported and not counted."""
    def edit(bag, w):
        ref_t, raws = bag.raw("/cdpr/reference")
        t = ref_t * 1e-9
        cut = (t > 20.0) & (t < 22.0)
        w.add_topic("/cdpr/reference", bag.topics["/cdpr/reference"])
        for tn, r, c in zip(ref_t.tolist(), raws, cut):
            if not c:
                w.write_raw("/cdpr/reference", tn, r)
    bag = copy_bag(CDPR, tmp_path / "refgap", skip={"/cdpr/reference"}, edit=edit)
    full = _json(cli("estimate", CDPR, "--json"))
    out = _json(cli("estimate", bag, "--json"))
    assert any("/cdpr/reference: 1 recording gap" in w for w in out["warnings"]), out["warnings"]
    t = np.asarray(__import__("cablelab.bags", fromlist=["open_bag"]).open_bag(CDPR)
                   .joint_state("/cdpr/cable_tensions").t)
    inside = int(((t > 20.0) & (t < 22.0)).sum())
    assert inside > 0 and full["samples"] - inside - 2 <= out["samples"] <= full["samples"] - inside + 2
    assert abs(out["mass"]["mean"] - full["mass"]["mean"]) < 0.01 * full["mass"]["mean"]


def test_report_page_shows_the_input_warnings(cli, tmp_path):
    """The HTML report carries the same warning lines as the JSON (a gap here)."""
    bag = axis_bag(tmp_path / "gap", keep=lambda t: ~((t > 12.0) & (t < 15.0)))
    out = _json(cli("report", bag, "-o", tmp_path / "rep", "--json", "--folds", "3"))
    page = (tmp_path / "rep" / "index.html").read_text()
    assert out["warnings"] and "Input warnings" in page
    assert all(html.escape(w) in page for w in out["warnings"])
