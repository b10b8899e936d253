"""Run the hostile cases of issue 14 through ``cablelab.cli.main`` (in-process) and print the
markdown table of docs/robustness.md: case, command, exit status, the one stderr line or the
warnings (nothing here is written by hand).

    ./run python bench/robustness_table.py
"""
from __future__ import annotations

import contextlib
import io
import json
import shutil
import sys
import tempfile
from pathlib import Path

import numpy as np
import yaml

REPO = Path(__file__).resolve().parent.parent
EMPS, CDPR = REPO / "bags" / "emps", REPO / "bags" / "cdpr_m1_reference"
DESC = "{plant: axis, axis: {joint_type: prismatic}}"


def run(argv):
    from cablelab.cli import main

    out, err = io.StringIO(), io.StringIO()
    with contextlib.redirect_stdout(out), contextlib.redirect_stderr(err):
        try:
            code = main([str(a) for a in argv])
        except SystemExit as exc:
            code = exc.code
    return code, out.getvalue(), err.getvalue()


def axis_bag(dst, stamps=None, keep=None, log=None, effort=None):  # log: header stamps != log times
    from cablelab.bags import BagWriter, open_bag

    bag = open_bag(EMPS)
    js = bag.joint_state("/axis/joint_states")
    t = js.t.copy() if stamps is None else stamps(js.t.copy())
    k = np.ones(t.size, bool) if keep is None else keep(js.t)
    eff = js.effort if effort is None else effort(js.effort.copy())
    kw = {} if log is None else {"log_time": js.t[k]}
    with BagWriter(dst) as w:
        w.write_description(bag.description_yaml, t=float(t[k].min()))
        w.write_joint_states("/axis/joint_states", t[k], js.names, js.position[k], js.velocity[k], eff[k], **kw)
    return dst


def table_row(name, argv, d) -> str:
    """One markdown row: case, command, exit status, the stderr line or the JSON warnings (and
    the identified M or estimated mass)."""
    code, out, err = run(argv)
    if code == 0:
        try:
            js = json.loads(out)
            what = "; ".join(js.get("warnings", [])) or "(no warning)"
            if "M" in js.get("params", {}):
                what += f" -> M = {js['params']['M']['value']:.2f} kg from {js['samples']} samples"
            elif isinstance(js.get("mass"), dict):
                what += f" -> mass {js['mass']['mean']:.1f} kg"
            elif "m" in js.get("params", {}) and isinstance(js["params"]["m"], dict):
                what += f" -> m = {js['params']['m']['value']:.1f} kg"
        except ValueError:
            what = out.strip().splitlines()[0] if out.strip() else ""
    else:
        what = err.strip()
    what = what.replace(str(d) + "/", "").replace(str(REPO) + "/", "").replace("|", "\\|")
    cmd = "cablelab " + " ".join(str(a).replace(str(d) + "/", "").replace(str(REPO) + "/", "")
                                 for a in argv)
    return f"| {name} | `{cmd}` | {code} | {what} |"


def main() -> int:
    d = Path(tempfile.mkdtemp(prefix="cablelab-robust-"))
    try:
        rows = []
        mid = 12.42

        def sh(t, dt):
            t[t > mid] += dt
            return t

        def rev(t):
            i = np.searchsorted(t, mid)
            t[i:i + 100] = t[i:i + 100][::-1].copy()
            return t

        def nan(e):
            e[1000:1037] = np.nan
            return e

        gap = axis_bag(d / "gap", keep=lambda t: ~((t > mid) & (t < mid + 3)))
        back = axis_bag(d / "jump_back", stamps=lambda t: sh(t, -0.5), log=True)
        fwd = axis_bag(d / "jump_fwd", stamps=lambda t: sh(t, 2.0), log=True)
        revb = axis_bag(d / "reversed", stamps=rev, log=True)
        ms = axis_bag(d / "ms", stamps=lambda t: 1000 * t, log=True)
        nanb = axis_bag(d / "nan", effort=nan)
        from cablelab.bags import open_bag

        doc = yaml.safe_load(open_bag(CDPR).description_yaml)
        doc["cdpr"]["cables"] = doc["cdpr"]["cables"][:5]
        five = d / "cdpr5.yaml"
        five.write_text(yaml.safe_dump(doc))
        csv = d / "text.csv"
        csv.write_text("t,q,f\n" + "\n".join(f"{0.001 * i:.3f},{'abc' if i == 16 else i},{i}" for i in range(300)))
        trunc = d / "killed"
        shutil.copytree(CDPR, trunc)
        (trunc / "metadata.yaml").unlink()
        mc = trunc / "cdpr_m1_reference.mcap"
        mc.write_bytes(mc.read_bytes()[: int(0.95 * mc.stat().st_size)])
        existing = d / "existing"
        existing.mkdir()
        cases = [
            ("reference: the complete EMPS recording", ["compare", EMPS, "--json"]),
            ("3 s gap in the recording", ["compare", gap, "--json"]),
            ("header clock jumps back 0.5 s", ["compare", back]),
            ("header clock jumps ahead 2 s", ["compare", fwd, "--json"]),
            ("100 stamps reversed", ["diagnose", revb]),
            ("stamps in ms", ["identify", ms]),
            ("37 NaN effort samples", ["compare", nanb, "--json"]),
            ("5-cable description on an 8-cable bag", ["compare", CDPR, "--description", five]),
            ("estimate --out = the input bag", ["estimate", CDPR, "--out", CDPR]),
            ("estimate --out existing, no --overwrite", ["estimate", CDPR, "--out", existing]),
            ("CSV with a text cell", ["import", csv, "--plant", "axis", "--map", "time=t,position=q,effort=f",
                                      "--description", DESC, "-o", d / "imp"]),
            ("--baseline none (no effects left)", ["compare", EMPS, "--baseline", "none"]),
            ("diagnose --alpha 2", ["diagnose", EMPS, "--alpha", "2"]),
            ("replay --rate nan", ["replay", EMPS, "--rate", "nan"]),
            ("replay --topics /nope", ["replay", EMPS, "--topics", "/nope"]),
            ("record --duration -1", ["record", "-o", d / "rec", "--plant", "axis", "--duration", "-1"]),
            ("record into a missing directory", ["record", "-o", d / "no" / "rec", "--plant", "axis"]),
            ("killed recording, no --recover", ["compare", trunc]),
            ("killed recording, estimate --recover", ["estimate", trunc, "--recover", "--json"]),
            ("repair the killed recording", ["repair", trunc, "-o", d / "repaired"]),
            ("unknown option", ["compare", EMPS, "--frob"]),
        ]
        print("| case | command | exit | stderr line / warnings |")
        print("|---|---|---|---|")
        for name, argv in cases:
            print(table_row(name, argv, d))
        silent_table(d)
    finally:
        shutil.rmtree(d, ignore_errors=True)
    return 0


# ============================================================ block: contradicting measurements and
# impossible results (docs/robustness.md, section of the same name)

def _emps_velocity(dst, factor):
    """The EMPS recording with a measured velocity = factor x the derivative of its position."""
    from cablelab.bags import BagWriter, open_bag
    from cablelab.filters import lowpass

    bag = open_bag(EMPS)
    js = bag.joint_state("/axis/joint_states")
    v = np.gradient(lowpass(js.position[:, 0], 1000.0, 100.0), js.t)
    with BagWriter(dst) as w:
        w.write_description(bag.description_yaml, t=float(js.t[0]))
        w.write_joint_states("/axis/joint_states", js.t, js.names, js.position, factor * v[:, None], js.effort)
    return dst


def _edit_topic(src, dst, topic, fn):
    """A copy of ``src`` with ``topic`` (JointState or PoseStamped) rewritten by ``fn(series, w)``."""
    from cablelab.bags import BagWriter, open_bag

    bag = open_bag(src)
    with BagWriter(dst) as w:
        for t, typ in bag.topics.items():
            if t == topic:
                continue
            w.add_topic(t, typ, transient_local=t == "/plant_description")
            t_ns, raws = bag.raw(t)
            for tn, r in zip(t_ns.tolist(), raws):
                w.write_raw(t, tn, r)
        fn(bag, w)
    return dst


def _slow_axis(dst, fs):
    from cablelab.bags import BagWriter
    from cablelab.description import load_description
    from cablelab.plants.axis.sim import AxisTruth
    from cablelab.plants.axis.truth import simulate_axis

    desc = load_description(DESC)
    r = simulate_axis(desc, AxisTruth(inertia=2.0, viscous=5.0, coulomb=0.0, timestep=1e-3),
                      duration=60, fs=fs, seed=1)
    with BagWriter(dst) as w:
        w.write_description(desc.to_yaml(), t=0.0)
        w.write_joint_states("/axis/joint_states", r.t + 1.0, ["joint"], r.q[:, None], None, r.effort[:, None])
    return dst


def silent_table(d) -> None:
    """The second table of docs/robustness.md: measurements that contradict each other and
    results that are physically impossible (each an error or a loud warning)."""
    from cablelab.bags import open_bag

    crane = REPO / "bags" / "crane_control"
    doc = yaml.safe_load(open_bag(CDPR).description_yaml)
    below, coinc = d / "cdpr_below.yaml", d / "cdpr_coincident.yaml"
    b = yaml.safe_load(yaml.safe_dump(doc))
    for c in b["cdpr"]["cables"]:
        c["exit_point"][2] = -3.0
    below.write_text(yaml.safe_dump(b))
    c2 = yaml.safe_load(yaml.safe_dump(doc))
    c2["cdpr"]["cables"][1] = dict(c2["cdpr"]["cables"][0])
    coinc.write_text(yaml.safe_dump(c2))

    def zero(bag, w):
        s = bag.joint_state("/cdpr/cable_tensions")
        w.write_joint_states("/cdpr/cable_tensions", s.t, s.names, None, None, np.zeros_like(s.effort))

    def negative(bag, w):
        s = bag.joint_state("/cdpr/cable_tensions")
        w.write_joint_states("/cdpr/cable_tensions", s.t, s.names, None, None, -s.effort)

    def renamed(bag, w):
        s = bag.joint_state("/cdpr/cable_tensions")
        w.write_joint_states("/cdpr/cable_tensions", s.t, [f"cable_{i}" for i in range(8)], None, None, s.effort)

    def degrees(bag, w):
        s = bag.joint_state("/crane/joint_states")
        q = s.position.copy()
        q[:, :2] = np.rad2deg(q[:, :2])
        w.write_joint_states("/crane/joint_states", s.t, s.names, q, s.velocity, s.effort)

    def frozen(bag, w):
        p = bag.pose("/crane/payload_pose")
        w.write_poses("/crane/payload_pose", p.t, np.repeat(p.position[:1], len(p.t), axis=0), p.quaternion)

    hz1 = d / "hz1.csv"
    t = np.arange(600.0)
    q = 0.1 * np.sin(2 * np.pi * t / 40) + 0.05 * np.sin(2 * np.pi * t / 13)
    hz1.write_text("t,q,f\n" + "".join(f"{int(a)},{float(b)!r},{float(c)!r}\n" for a, b, c in
                                        zip(t, q, 3 * np.gradient(np.gradient(q)) + 2 * np.gradient(q))))
    imp = ["import", hz1, "--plant", "axis", "--description", DESC]
    mapping = "time=t,position=q,effort=f"
    cases = [
        ("control: measured velocity = derivative of position", ["compare", _emps_velocity(d / "v_ok", 1.0), "--json"]),
        ("measured velocity with its sign flipped", ["diagnose", _emps_velocity(d / "v_flip", -1.0), "--json"]),
        ("measured velocity in deg/s", ["compare", _emps_velocity(d / "v_deg", 57.29578), "--json"]),
        ("CDPR exit points below the platform", ["estimate", CDPR, "--description", below]),
        ("CDPR: two coincident cables", ["identify", CDPR, "--description", coinc]),
        ("CDPR: all tensions 0", ["estimate", _edit_topic(CDPR, d / "zero", "/cdpr/cable_tensions", zero)]),
        ("CDPR: tensions with the wrong sign", ["estimate", _edit_topic(CDPR, d / "neg", "/cdpr/cable_tensions",
                                                                          negative), "--json"]),
        ("CDPR: cables named cable_0..cable_7", ["compare", _edit_topic(CDPR, d / "names", "/cdpr/cable_tensions",
                                                                          renamed)]),
        ("crane slew / luff in degrees", ["estimate", _edit_topic(crane, d / "deg", "/crane/joint_states", degrees)]),
        ("crane payload pose frozen", ["diagnose", _edit_topic(crane, d / "frozen", "/crane/payload_pose", frozen)]),
        ("axis sampled at 10 Hz (true M = 2 kg)", ["compare", _slow_axis(d / "slow10", 10.0), "--json"]),
        ("axis sampled at 5 Hz (motion up to 1.5 Hz)", ["compare", _slow_axis(d / "slow5", 5.0), "--json"]),
        ("1 Hz integer-second stamps", imp + ["--map", mapping, "-o", d / "hz1"]),
        ("1 Hz stamps declared seconds", imp + ["--map", mapping, "-o", d / "hz1s", "--time-unit", "s", "--json"]),
        ("--map effort=f/0", imp + ["--map", "time=t,position=q,effort=f/0", "-o", d / "div0"]),
        ("--tensions on an axis bag", ["compare", EMPS, "--tensions", "motor"]),
        ("--pose on a crane bag", ["estimate", crane, "--pose", "measured"]),
    ]
    print()
    print("| case | command | exit | stderr line / warnings |")
    print("|---|---|---|---|")
    for name, argv in cases:
        print(table_row(name, argv, d))


if __name__ == "__main__":
    sys.exit(main())
