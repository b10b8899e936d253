"""No silent wrong result: measurements that contradict each other and results that are
physically impossible are errors or loud warnings, never a confident number.

Classes (docs/robustness.md "Contradicting measurements and impossible results"): a measured
velocity against the derivative of its position; CDPR geometry that cannot hold the platform and
loads that are all zero; masses that are not > 0; crane angles in degrees and a frozen payload
pose; slow recordings whose motion the default filter would remove; 1 Hz integer-second stamps;
a zero or non-finite ``--map`` scale; options of another plant; misleading messages. Oracles:
the fit of the complete EMPS recording without a velocity, the truth of a simulated axis, the
reference bags (controls: no warning).
"""
from __future__ import annotations

import json
import math

import numpy as np
import pytest
import yaml
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from robust_helpers import CDPR, EMPS, REPO, copy_bag, tree_snapshot

CRANE = REPO / "bags" / "crane_control"
FUZZ = settings(max_examples=12, deadline=None, derandomize=True,
                suppress_health_check=[HealthCheck.function_scoped_fixture, HealthCheck.too_slow])


def _json(res):
    assert res.code == 0, res.err
    return json.loads(res.out)


def _one_line_error(res, *needles):
    assert res.code == 2 and res.out == "", (res.code, res.out, res.err)
    assert len(res.err_lines) == 1, res.err
    for n in needles:
        assert n in res.err, res.err


# ------------------------------------------------------------------ measured velocity vs position

def _emps_velocity(dst, factor=1.0):
    """The EMPS recording with a measured velocity: the derivative of its position (100 Hz
    low-pass, as the EMPS reference) times ``factor`` (-1: sign flipped, 57.3: deg/s)."""
    from cablelab.bags import BagWriter, open_bag
    from cablelab.filters import lowpass

    bag = open_bag(EMPS)
    js = bag.joint_state("/axis/joint_states")
    v = np.gradient(lowpass(js.position[:, 0], 1000.0, 100.0), js.t)
    with BagWriter(dst) as w:
        w.write_description(bag.description_yaml, t=float(js.t[0]))
        w.write_joint_states("/axis/joint_states", js.t, js.names, js.position, factor * v[:, None],
                             js.effort)
    return dst


@pytest.fixture(scope="module")
def emps_fit():
    """(M, Fv) of the EMPS recording as shipped (no velocity: derived from the position)."""
    from cablelab.cli import main  # noqa: F401
    from cablelab.workbench import build_model, compare, load

    plant, desc, ds = load(EMPS)
    p = compare(ds, build_model(plant, desc)).params
    return p["M"]["value"], p["Fv"]["value"]


def test_correct_velocity_is_used_without_warning(cli, tmp_path, emps_fit):
    out = _json(cli("compare", _emps_velocity(tmp_path / "ok"), "--json"))
    assert out["warnings"] == []
    assert abs(out["params"]["Fv"]["value"] - emps_fit[1]) < 0.05 * emps_fit[1]


@pytest.mark.parametrize("factor, what", [(-1.0, "sign flipped"), (57.29578, "57.3x"),
                                          (1 / 9.5493, "0.105x")])
def test_contradicting_velocity_is_replaced_and_said(cli, tmp_path, emps_fit, factor, what):
    """Sign flipped, deg/s, rpm: a loud warning naming the joint, and the fit equals the fit with
    the velocity derived from the position (before: Fv 0.136 instead of 7.8 for deg/s)."""
    bag = _emps_velocity(tmp_path / "bad", factor)
    out = _json(cli("compare", bag, "--json"))
    w = [x for x in out["warnings"] if "measured velocity contradicts" in x]
    assert len(w) == 1 and what in w[0] and "joint" in w[0] and "NOT USED" in w[0], out["warnings"]
    assert out["params"]["M"]["value"] == pytest.approx(emps_fit[0], rel=1e-6)
    assert out["params"]["Fv"]["value"] == pytest.approx(emps_fit[1], rel=1e-6)


def test_flipped_velocity_does_not_hide_coulomb_friction(cli, tmp_path):
    out = _json(cli("diagnose", _emps_velocity(tmp_path / "flip", -1.0), "--json"))
    assert out["ranking"][0]["effect"] == "joint_coulomb_friction" and out["ranking"][0]["significant"]
    assert any("sign flipped" in x for x in out["warnings"])


def _quantized_motion(seed):
    rng = np.random.default_rng(seed)
    t = np.arange(0, 8, 1e-3)
    f = rng.uniform(0.2, 2.0, 3)
    q = sum(rng.uniform(0.02, 0.1) * np.sin(2 * np.pi * fi * t + rng.uniform(0, 6)) for fi in f)
    v = np.gradient(q, t)
    quantum = 10 ** rng.uniform(-7, -5)
    return t, np.round(q / quantum) * quantum, v


@FUZZ
@given(seed=st.integers(0, 10_000), sign=st.sampled_from([1.0, -1.0]),
       log_scale=st.floats(-3.0, 3.0).filter(lambda x: abs(abs(x) - math.log(1.5)) > 0.15))
def test_velocity_corruption_flagged_iff_beyond_tolerance(seed, sign, log_scale):
    """A measured velocity scaled by s (sign and magnitude random) on a quantized encoder: flagged
    exactly when s < 0 or |s| is outside [1/1.5, 1.5] (a margin around the tolerance edge is
    not drawn)."""
    from cablelab.velocity import VELOCITY_SCALE_TOLERANCE, velocity_agreement, velocity_contradiction

    t, q, v = _quantized_motion(seed)
    s = sign * math.exp(log_scale)
    flagged = bool(velocity_contradiction(velocity_agreement(t, q, s * v)))
    beyond = s < 0 or not 1 / VELOCITY_SCALE_TOLERANCE <= abs(s) <= VELOCITY_SCALE_TOLERANCE
    assert flagged == beyond, (s, velocity_agreement(t, q, s * v))


@FUZZ
@given(seed=st.integers(0, 10_000))
def test_unrelated_velocity_is_flagged(seed):
    from cablelab.velocity import velocity_agreement, velocity_contradiction

    t, q, v = _quantized_motion(seed)
    rng = np.random.default_rng(seed + 1)
    # another joint's velocity: the same size, frequencies in a band of its own (3-5 Hz)
    other = sum(np.cos(2 * np.pi * f * t + rng.uniform(0, 6)) for f in rng.uniform(3, 5, 3))
    other *= np.std(v) / np.std(other)
    assert velocity_contradiction(velocity_agreement(t, q, other)) != ""


@pytest.mark.parametrize("bag", ["emps", "cdpr_m1_reference", "cdpr_m2_fast", "cdpr_m2_pulleys_unknown",
                                 "crane_control", "crane_no_counterbalance", "crane_tilt"])
def test_reference_bags_have_no_contradiction(bag):
    """Controls: every shipped bag passes the new checks without a velocity, geometry or rate
    warning (the time-base warnings of crane_tilt's dropouts are its own)."""
    from cablelab.bagcheck import check_bag
    from cablelab.bags import open_bag
    from cablelab.registry import get_plant

    b = open_bag(REPO / "bags" / bag)
    chk = check_bag(b, get_plant(b.description.plant), b.description, {})
    assert chk.derived_velocity == {}
    assert not [w for w in chk.warnings if "NaN/inf" not in w], chk.warnings


# ------------------------------------------------------------------ CDPR: geometry and loads

def _cdpr_desc(tmp_path, edit, name="d"):
    from cablelab.bags import open_bag

    d = yaml.safe_load(open_bag(CDPR).description_yaml)
    edit(d["cdpr"]["cables"])
    p = tmp_path / f"{name}.yaml"
    p.write_text(yaml.safe_dump(d))
    return p


def _below(cables):
    for c in cables:
        c["exit_point"][2] = -3.0


def _coincident(cables):
    cables[1] = dict(cables[0])


@pytest.mark.parametrize("edit, needle", [(_below, "no cable pulls up"),
                                          (_coincident, "cables 1 and 2 have the same exit point")])
@pytest.mark.parametrize("verb", ["estimate", "identify", "diagnose"])
def test_impossible_cdpr_geometry_is_an_error(cli, tmp_path, edit, needle, verb):
    """Before: exit points below the platform gave -904 kg with ``warnings: []``, coincident
    cables 1120 kg."""
    res = cli(verb, CDPR, "--description", _cdpr_desc(tmp_path, edit), "--json")
    _one_line_error(res, needle, "plant description")


def test_all_zero_tensions_are_an_error(cli, tmp_path):
    def edit(bag, w):
        s = bag.joint_state("/cdpr/cable_tensions")
        w.write_joint_states("/cdpr/cable_tensions", s.t, s.names, None, None, np.zeros_like(s.effort))
    bag = copy_bag(CDPR, tmp_path / "zero", skip={"/cdpr/cable_tensions"}, edit=edit)
    before = tree_snapshot(bag)
    for verb in ("estimate", "compare"):
        _one_line_error(cli(verb, bag, "--json"), "/cdpr/cable_tensions", "exactly 0")
    assert tree_snapshot(bag) == before


def test_negative_mass_is_flagged_in_every_verb(cli, tmp_path):
    """Tensions with the wrong sign: the cables push, the weight they carry is negative. Every
    verb that prints a mass says PHYSICALLY IMPOSSIBLE (estimate: the mean is < 0; identify and
    compare: the bounded fit sits at m = 0)."""
    def edit(bag, w):
        s = bag.joint_state("/cdpr/cable_tensions")
        w.write_joint_states("/cdpr/cable_tensions", s.t, s.names, None, None, -s.effort)
    bag = copy_bag(CDPR, tmp_path / "neg", skip={"/cdpr/cable_tensions"}, edit=edit)
    est = _json(cli("estimate", bag, "--json"))
    assert est["mass"]["mean"] < 0
    assert any("PHYSICALLY IMPOSSIBLE: mass" in w for w in est["warnings"]), est["warnings"]
    for verb in ("identify", "compare"):
        out = _json(cli(verb, bag, "--json", *(["--folds", "0"] if verb == "identify" else [])))
        assert out["params"]["m"]["value"] <= 0
        assert any("PHYSICALLY IMPOSSIBLE: m =" in w for w in out["warnings"]), out["warnings"]
    clean = _json(cli("identify", CDPR, "--json", "--folds", "0"))
    assert not any("IMPOSSIBLE" in w for w in clean["warnings"])


def test_impossible_parameters_oracle():
    from cablelab.plausibility import impossible_parameters, positive_parameters

    pos = positive_parameters(["cdpr_gravity", "axis_inertia", "crane_rigid_body"])
    assert {"m", "M", "I_tot"} <= pos
    assert impossible_parameters({"m": {"value": -904.0, "unit": "kg"}}, pos)
    assert impossible_parameters({"M": {"value": 0.0, "unit": "kg"}}, pos)
    assert not impossible_parameters({"M": {"value": 0.0, "unit": "kg", "fixed": True}}, pos)
    assert not impossible_parameters({"m": {"value": 488.0, "unit": "kg"}}, pos)
    assert not impossible_parameters({"Fv": {"value": -1.0, "unit": "N s/m"}}, pos)


@FUZZ
@given(data=st.data())
def test_random_cdpr_geometry_never_prints_an_impossible_mass(cli, tmp_path, data):
    """Random exit and anchor points (anything from a valid frame to points below the platform,
    coincident or collinear cables): ``estimate`` on the reference recording either refuses with
    one line, or prints a positive mass, or says PHYSICALLY IMPOSSIBLE."""
    coord = st.floats(-4.0, 4.0, allow_nan=False)
    n = 8

    def edit(cables):
        for c in cables[:n]:
            c["exit_point"] = [data.draw(coord), data.draw(coord), data.draw(st.floats(-4.0, 4.0))]
            c["anchor_point"] = [data.draw(st.floats(-1, 1)), data.draw(st.floats(-1, 1)),
                                 data.draw(st.floats(-1, 1))]
        if data.draw(st.booleans()):
            cables[3] = dict(cables[2])
    res = cli("estimate", CDPR, "--description", _cdpr_desc(tmp_path, edit, "rand"), "--json")
    if res.code == 2:
        assert len(res.err_lines) == 1 and res.out == ""
        return
    out = _json(res)
    m = out["mass"]["mean"]
    assert (m is not None and m > 0) or any("PHYSICALLY IMPOSSIBLE" in w for w in out["warnings"])


# ------------------------------------------------------------------ crane: degrees, frozen pose

def _crane_degrees(bag, w):
    s = bag.joint_state("/crane/joint_states")
    q = s.position.copy()
    q[:, :2] = np.rad2deg(q[:, :2])
    w.write_joint_states("/crane/joint_states", s.t, s.names, q, s.velocity, s.effort)


def _crane_frozen(bag, w):
    p = bag.pose("/crane/payload_pose")
    w.write_poses("/crane/payload_pose", p.t, np.repeat(p.position[:1], len(p.t), axis=0), p.quaternion)


@pytest.mark.parametrize("edit, topic, needle", [
    (_crane_degrees, "/crane/joint_states", "look like degrees"),
    (_crane_frozen, "/crane/payload_pose", "is frozen"),
])
@pytest.mark.parametrize("verb", ["estimate", "diagnose"])
def test_crane_contradictions_are_errors(cli, tmp_path, edit, topic, needle, verb):
    """Before: 291-degree swings without a word."""
    bag = copy_bag(CRANE, tmp_path / "c", skip={topic}, edit=edit)
    _one_line_error(cli(verb, bag, "--json"), needle, topic)


def test_crane_luff_in_degrees_without_tip_pose():
    from cablelab.errors import CablelabError
    from cablelab.plants.crane.dataset import check_measurements

    class S:  # a joint-state series
        names = ["slew", "luff", "hoist"]
        t = np.linspace(0, 10, 200)
        position = np.column_stack([np.linspace(-30, 30, 200), np.linspace(20, 60, 200), np.full(200, 0.8)])

    class B:
        path = "bag"

    with pytest.raises(CablelabError, match="look like degrees"):
        check_measurements(B, 1.0, S)
    S.position = np.deg2rad(S.position) * [1, 1, 0] + [0, 0, 0.8]
    assert check_measurements(B, 1.0, S) == []


# ------------------------------------------------------------------ slow recordings

def _slow_axis(dst, fs):
    from cablelab.bags import BagWriter
    from cablelab.description import load_description
    from cablelab.plants.axis.sim import AxisTruth
    from cablelab.plants.axis.truth import simulate_axis

    d = load_description("{plant: axis, axis: {joint_type: prismatic}}")
    run = simulate_axis(d, AxisTruth(inertia=2.0, viscous=5.0, coulomb=0.0, timestep=1e-3),
                        duration=60, fs=fs, seed=1)
    with BagWriter(dst) as w:
        w.write_description(d.to_yaml(), t=0.0)
        w.write_joint_states("/axis/joint_states", run.t + 1.0, ["joint"], run.q[:, None], None,
                             run.effort[:, None])
    return dst


def test_slow_recording_keeps_its_motion(cli, tmp_path):
    """10 Hz sampling of a motion up to 1.5 Hz: fs / 10 = 1 Hz filtered the motion out (M 3.11 kg
    for a true 2.0, 85 % NRMSE, no warning). Now the cut-off follows the motion's band and the
    derivatives are the spline's: the simulated truth comes back."""
    out = _json(cli("compare", _slow_axis(tmp_path / "s10", 10.0), "--json"))
    assert out["params"]["M"]["value"] == pytest.approx(2.0, rel=0.03)
    assert out["params"]["Fv"]["value"] == pytest.approx(5.0, rel=0.03)
    assert out["channels"]["joint"]["nrmse"] < 0.05
    assert out["warnings"] == []


def test_too_slow_recording_warns(cli, tmp_path):
    out = _json(cli("compare", _slow_axis(tmp_path / "s5", 5.0), "--json"))
    assert any("too close to the Nyquist frequency" in w for w in out["warnings"]), out["warnings"]


def test_motion_cutoff_leaves_fast_recordings_alone():
    """At 1 kHz (EMPS) the motion is far below fs / 10: the default cut-off is kept."""
    from cablelab.bags import open_bag
    from cablelab.conditioning import motion_cutoff

    js = open_bag(EMPS).joint_state("/axis/joint_states")
    assert motion_cutoff(js.position[:, 0], 1000.0, 100.0) == (100.0, [])


def test_spline_derivatives_are_unbiased_near_nyquist():
    """Oracle: the closed-form derivatives of a 1.5 Hz sine sampled at 10 Hz (central differences
    give 0.86 x the velocity and 0.74 x the acceleration)."""
    from cablelab.conditioning import derivatives

    fs, f = 10.0, 1.5
    t = np.arange(400) / fs
    w = 2 * np.pi * f
    x = np.sin(w * t)
    _, xd, xdd = derivatives(x, fs, None, method="spline")
    mid = slice(20, -20)
    assert np.max(np.abs(xd[mid] - w * np.cos(w * t[mid]))) < 0.01 * w
    assert np.max(np.abs(xdd[mid] + w * w * x[mid])) < 0.01 * w * w
    _, xd_c, _ = derivatives(x, fs, None)
    assert np.max(np.abs(xd_c[mid])) < 0.9 * w


# ------------------------------------------------------------------ stamps in seconds at 1 Hz

def _csv_1hz(path, t0=0):
    t = np.arange(600.0)
    q = 0.1 * np.sin(2 * np.pi * t / 40) + 0.05 * np.sin(2 * np.pi * t / 13)
    f = 3.0 * np.gradient(np.gradient(q)) + 2.0 * np.gradient(q)
    path.write_text("t,q,f\n" + "".join(f"{int(a) + t0},{float(b)!r},{float(c)!r}\n" for a, b, c in zip(t, q, f)))
    return path


DESC = "{plant: axis, axis: {joint_type: prismatic}}"


def test_one_hz_integer_seconds_need_and_accept_time_unit(cli, tmp_path):
    csv = _csv_1hz(tmp_path / "hz1.csv")
    args = ("import", csv, "--plant", "axis", "--map", "time=t,position=q,effort=f", "--description", DESC)
    _one_line_error(cli(*args, "-o", tmp_path / "no"), "look like milliseconds", "--time-unit s")
    assert not (tmp_path / "no").exists()
    assert cli(*args, "-o", tmp_path / "b", "--time-unit", "s").code == 0
    _one_line_error(cli("compare", tmp_path / "b", "--json"), "--time-unit s")
    out = _json(cli("compare", tmp_path / "b", "--json", "--time-unit", "s"))
    assert out["samples"] > 400


def test_epoch_seconds_are_not_milliseconds():
    from cablelab.timebase import Limits, check_stamps

    t = 1.7e9 + np.arange(600.0)                      # 1 Hz, integer UNIX seconds (2023)
    assert not check_stamps(t).milliseconds
    assert check_stamps(np.arange(600.0)).milliseconds   # ambiguous: refused unless told
    assert not check_stamps(np.arange(600.0), limits=Limits(time_unit="s")).milliseconds
    assert check_stamps(1.7e12 + np.arange(600.0)).milliseconds   # UNIX ms
    # a recorder's own clock that runs with the stamps says they are seconds
    assert not check_stamps(np.arange(600.0), t_log=50.0 + np.arange(600.0) * 1.0001).milliseconds
    assert check_stamps(np.arange(600.0) * 1000.0, t_log=np.arange(600.0)).milliseconds


# ------------------------------------------------------------------ --map scales, plant options

@pytest.mark.parametrize("spec, needle", [
    ("time=t,position=q,effort=f/0", "divisor '0' = 0"),
    ("time=t,position=q,effort=0*f", "scale factor '0' = 0"),
    ("time=t,position=q,effort=inf*f", "scale factor 'inf'"),
    ("time=t,position=q,effort=f/z", "divisor column 'z' is 0"),
])
def test_map_scale_zero_or_non_finite_is_an_error(cli, tmp_path, spec, needle):
    csv = tmp_path / "a.csv"
    t = np.arange(300) * 0.01
    csv.write_text("t,q,f,z\n" + "".join(f"{a},{np.sin(a)},{np.cos(a)},{0 if i == 7 else 1}\n"
                                         for i, a in enumerate(t)))
    res = cli("import", csv, "--plant", "axis", "--map", spec, "--description", DESC, "-o", tmp_path / "o")
    _one_line_error(res, needle)
    assert not (tmp_path / "o").exists()


@pytest.mark.parametrize("verb, opt", [("compare", ("--tensions", "motor")),
                                       ("identify", ("--tensions", "dynamometer")),
                                       ("estimate", ("--pose", "measured"))])
def test_option_of_another_plant_is_an_error(cli, verb, opt):
    bag = CRANE if verb == "estimate" else EMPS
    _one_line_error(cli(verb, bag, *opt, "--json"), opt[0], "plant cdpr only")


def test_cdpr_options_still_work(cli):
    out = _json(cli("estimate", CDPR, "--tensions", "dynamometer", "--pose", "desired", "--json"))
    assert out["mass"]["mean"] == pytest.approx(488.0, rel=0.01)


# ------------------------------------------------------------------ messages that say what is wrong

def test_same_count_other_names_says_which(cli, tmp_path):
    """Before: "has 8 cables (cable_0..cable_7) but the description has 8 cables"."""
    def edit(bag, w):
        s = bag.joint_state("/cdpr/cable_tensions")
        names = [f"cable_{i}" for i in range(8)]
        w.write_joint_states("/cdpr/cable_tensions", s.t, names, None, None, s.effort)
    bag = copy_bag(CDPR, tmp_path / "names", skip={"/cdpr/cable_tensions"}, edit=edit)
    res = cli("compare", bag, "--json")
    _one_line_error(res, "missing cable_8", "unexpected cable_0")
    assert "but the plant description has 8" not in res.err


def test_free_run_fit_starts_from_the_models_own_parameters(tmp_path):
    """identify --simulation on a model without Coulomb friction: no "start value of Fc"
    (Fc is not in the model); a non-physical inverse-model start names what is wrong."""
    from cablelab.description import load_description
    from cablelab.errors import CablelabError
    from cablelab.plants.axis.dataset import dataset_from_arrays
    from cablelab.plants.axis.freerun import fit_free_run
    from cablelab.plants.axis.sim import AxisTruth
    from cablelab.plants.axis.truth import simulate_axis

    d = load_description(DESC)
    run = simulate_axis(d, AxisTruth(inertia=2.0, viscous=5.0, coulomb=0.0, timestep=1e-3),
                        duration=6, fs=200, seed=2)
    ds = dataset_from_arrays(run.t, run.q, run.effort, d)
    fit = fit_free_run(ds, {"M": 2.2, "Fv": 4.5}, max_iter=2)
    assert set(fit.params) == {"M", "Fv"}
    with pytest.raises(CablelabError, match=r"viscous friction Fv = -3.*not physical"):
        fit_free_run(ds, {"M": 2.2, "Fv": -3.0}, max_iter=2)


@FUZZ
@given(seed=st.integers(0, 10_000), degrees=st.booleans(), boom=st.floats(0.5, 20.0),
       with_tip=st.booleans())
def test_crane_degrees_flagged_iff_degrees(seed, degrees, boom, with_tip):
    """Random slew / luff motions in radians (luff 0.1-1.3 rad) with a measured boom tip (1 % of
    the boom of marker noise) or without one: refused exactly when the angles are in degrees."""
    from cablelab.errors import CablelabError
    from cablelab.plants.crane.kinematics import boom_tip
    from cablelab.plants.crane.dataset import check_measurements

    rng = np.random.default_rng(seed)
    t = np.linspace(0, 20, 400)
    alpha = rng.uniform(-1.5, 1.5) * np.sin(2 * np.pi * rng.uniform(0.02, 0.2) * t)
    beta = rng.uniform(0.1, 0.5) + rng.uniform(0.1, 0.8) * (1 + np.sin(2 * np.pi * rng.uniform(0.02, 0.2) * t)) / 2
    tip = boom_tip(alpha, beta, boom) + 0.01 * boom * rng.normal(size=(t.size, 3))
    q = np.column_stack([alpha, beta, np.full(t.size, 0.8)])
    if degrees:
        q[:, :2] = np.rad2deg(q[:, :2])

    class JS:
        names, position = ["slew", "luff", "hoist"], q
    JS.t = t

    class Tip:
        position = tip
    Tip.t = t

    class B:
        path = "bag"

    try:
        check_measurements(B, boom, JS, Tip if with_tip else None)
        raised = False
    except CablelabError as exc:
        raised = "degrees" in str(exc)
    assert raised == degrees


@FUZZ
@given(period=st.sampled_from([1.0, 2.0, 5.0]), start=st.sampled_from([0.0, 1.0, 1.6e9, 1.7e12]),
       unit=st.sampled_from(["auto", "s"]))
def test_integer_stamps_ms_only_when_ambiguous_or_epoch_ms(period, start, unit):
    """Integer stamps >= 1 apart: with --time-unit s never milliseconds; in auto, UNIX epoch
    seconds are seconds, epoch milliseconds and small (ambiguous) stamps are refused."""
    from cablelab.timebase import Limits, check_stamps

    t = start + period * np.arange(300.0)
    ms = check_stamps(t, limits=Limits(time_unit=unit)).milliseconds
    if unit == "s":
        assert not ms
    else:
        assert ms == (not 1e8 <= start < 1e10)
