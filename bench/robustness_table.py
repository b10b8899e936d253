"""Run the hostile cases through ``cablelab.cli.main`` (in-process) and print the
markdown table of docs/robustness.md: case, command, exit status, the one stderr line or the
warnings (nothing here is written by hand). The last table, the numeric-validation cases (ROS
parameters of the nodes, numeric options, description numbers, CSV cells), can be printed alone.

    ./run python bench/robustness_table.py              # every table
    ./run python bench/robustness_table.py --validation # the validation table only
"""
from __future__ import annotations

import contextlib
import io
import json
import os
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
    if "--validation" in sys.argv[1:]:
        return validation_table()
    d = Path(tempfile.mkdtemp(prefix="cablelab-robust-"))
    try:
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
        cases += output_and_integrity_cases(d)
        print("| case | command | exit | stderr line / warnings |")
        print("|---|---|---|---|")
        for name, argv in cases:
            print(table_row(name, argv, d))
        silent_table(d)
    finally:
        for p in _HOLDERS:
            p.kill()
            p.wait()
        shutil.rmtree(d, ignore_errors=True)
    print()
    return validation_table()


# ----------------------------------------------------------------------------- outputs, memory, bag integrity
# (data loss at output targets, bounds by the data, bags checked against themselves; the tests
# are test/core/test_output_safety.py, test_bounded_memory.py, test_bag_integrity.py)
_HOLDERS: list = []


def _chunked_emps(dst, per_chunk=500, edit=None):
    """The EMPS recording rewritten with a flush every ``per_chunk`` messages (50 chunks)."""
    from cablelab.bags import BagWriter, open_bag

    bag = open_bag(EMPS)
    js = bag.joint_state("/axis/joint_states")
    t = js.t.copy() if edit is None else edit(js.t.copy())
    with BagWriter(dst) as w:
        w.write_description(bag.description_yaml, t=0.0)
        for a in range(0, t.size, per_chunk):
            s = slice(a, a + per_chunk)
            w.write_joint_states("/axis/joint_states", t[s], js.names, js.position[s], js.velocity[s],
                                 js.effort[s])
            w.flush()
    return dst


def output_and_integrity_cases(d: Path) -> list:
    import subprocess

    import yaml as _yaml

    from cablelab.bags.salvage import _summary

    mydocs = d / "mydocs"
    (mydocs / "sub").mkdir(parents=True)
    (mydocs / "thesis.tex").write_text("\\chapter{mine}")
    precious = d / "precious.txt"
    precious.write_text("precious")
    inbag = d / "inbag"
    shutil.copytree(EMPS, inbag)
    fleet = d / "fleet"
    shutil.copytree(EMPS, fleet / "emps")
    site = d / "site"
    site.mkdir()
    (site / "index.html").write_text("<h1>mine</h1>")
    busy = d / "busy"
    holder = subprocess.Popen([sys.executable, "-c", "import sys, time; from cablelab.atomic import "
                               "lock_target; lock_target(sys.argv[1]); print(1, flush=True); time.sleep(600)",
                               str(busy)], stdout=subprocess.PIPE, text=True)
    holder.stdout.readline()
    _HOLDERS.append(holder)
    jump = axis_bag(d / "jump_1e6", stamps=lambda t: np.where(t > 10, t + 1e6, t), log=True)
    chunked = _chunked_emps(d / "chunked")
    mcap = next(chunked.glob("*.mcap"))
    data = bytearray(mcap.read_bytes())
    start = _summary(bytes(data))[2][20]
    data[start + 3000:start + 3400] = np.random.default_rng(0).integers(0, 256, 400, dtype=np.uint8).tobytes()
    mcap.write_bytes(bytes(data))
    split = d / "split"
    split.mkdir()
    a_bag = _chunked_emps(d / "a_part")
    shutil.copy(next(a_bag.glob("*.mcap")), split / "split_0.mcap")
    meta = _yaml.safe_load((a_bag / "metadata.yaml").read_text())
    info = meta["rosbag2_bagfile_information"]
    info["relative_file_paths"] = ["split_0.mcap", "split_1.mcap"]
    info["files"] = [dict(info["files"][0], path="split_0.mcap"),
                     dict(info["files"][0], path="split_1.mcap", message_count=12000)]
    info["message_count"] += 12000
    (split / "metadata.yaml").write_text(_yaml.safe_dump(meta))
    from cablelab.bags import BagWriter, open_bag

    js = open_bag(EMPS).joint_state("/axis/joint_states")
    desc = open_bag(EMPS).description_yaml
    two = d / "two_descriptions"
    with BagWriter(two) as w:
        w.write_strings("/plant_description", [0.0, 12.0], [desc, desc.replace("prismatic", "revolute")],
                        transient_local=True)
        w.write_joint_states("/axis/joint_states", js.t, js.names, js.position, js.velocity, js.effort)
    junk = d / "junk_description"
    with BagWriter(junk) as w:
        w.write_strings("/plant_description", [0.0], ["hello world"], transient_local=True)
        w.write_joint_states("/axis/joint_states", js.t, js.names, js.position, js.velocity, js.effort)
    imp = ["import", d / "x.csv", "--plant", "axis", "--map", "time=t,position=q,effort=f", "--description", DESC]
    (d / "x.csv").write_text("t,q,f\n" + "\n".join(f"{0.001 * i:.3f},{i},{i}" for i in range(300)))
    return [
        ("--overwrite onto a user's directory (thesis.tex, sub/)",
         ["report", EMPS, "-o", mydocs, "--overwrite"]),
        ("--overwrite onto a file", ["report", EMPS, "-o", precious, "--overwrite"]),
        ("output inside the bag of an .mcap input", ["report", inbag / "emps.mcap", "-o", inbag / "rep"]),
        ("--overwrite of the verb's own output", imp + ["-o", d / "own"]),
        ("(again, replacing it)", imp + ["-o", d / "own", "--overwrite"]),
        ("batch OUT = ROOT", ["batch", fleet, "-o", fleet]),
        ("batch OUT inside ROOT", ["batch", fleet, "-o", fleet / "out"]),
        ("batch into a user's directory with index.html", ["batch", fleet, "-o", site]),
        ("output being written by another process", imp + ["-o", busy]),
        ("1e6 s forward clock jump in a 25 s bag", ["identify", jump, "--json"]),
        ("--description /dev/zero", ["compare", EMPS, "--description", "/dev/zero"]),
        ("400 corrupted bytes in one of 50 chunks", ["compare", chunked]),
        ("(the same, --recover)", ["compare", chunked, "--recover", "--json"]),
        ("(the same, repair)", ["repair", chunked, "-o", d / "chunked_fixed"]),
        ("split bag missing one of its 2 files", ["compare", split]),
        ("(the same, --recover)", ["compare", split, "--recover", "--json"]),
        ("(the same, repair)", ["repair", split, "-o", d / "split_fixed"]),
        ("two different /plant_description messages", ["compare", two]),
        ("/plant_description that is not a mapping", ["compare", junk]),
    ]


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



# ================================================================================ numeric validation
# Every numeric input checked for type, range and shape before use: ROS parameters of the nodes,
# numeric CLI options, description numbers (YAML 1.2), CSV cells. Node cases run the node's real
# main in-process (rclpy initialised with the -p overrides; a valid case runs 0.05 s of sim time).

def run_node_main(package, role, argv):
    """``package --plant P --ros-args ...`` through its real main, in-process: (exit, stderr)."""
    from cablelab.ros.launch import release_domain_id, reserve_domain_id
    from cablelab.ros.runner import plant_main

    dom = reserve_domain_id(salt=4444)
    old = os.environ.get("ROS_DOMAIN_ID")
    os.environ["ROS_DOMAIN_ID"] = str(dom)
    err = io.StringIO()
    try:
        with contextlib.redirect_stderr(err), contextlib.redirect_stdout(io.StringIO()):
            try:
                code = plant_main(package, role, [str(a) for a in argv], "")
            except SystemExit as exc:
                code = exc.code
    finally:
        release_domain_id(dom)
        if old is None:
            os.environ.pop("ROS_DOMAIN_ID", None)
        else:
            os.environ["ROS_DOMAIN_ID"] = old
    return code, err.getvalue()


def validation_table() -> int:
    d = Path(tempfile.mkdtemp(prefix="cablelab-validation-"))
    try:
        doc = yaml.safe_load((REPO / "bags" / "cdpr_m1_reference" / "metadata.yaml").exists() and
                             __import__("cablelab.bags", fromlist=["open_bag"]).open_bag(CDPR).description_yaml)
        doc["cdpr"]["pulley_radius"] = 100
        big_pulley = d / "pulley100.yaml"
        big_pulley.write_text(yaml.safe_dump(doc))
        e2e3 = d / "inertia2e3.yaml"
        e2e3.write_text("plant: axis\naxis:\n  joint_type: prismatic\n  inertia: 2e3\n")
        dup = d / "dupkey.yaml"
        dup.write_text("plant: axis\naxis:\n  joint_type: prismatic\n  inertia: 2\n  inertia: 3\n")
        latin = d / "latin1.yaml"
        latin.write_bytes(b"plant: axis\naxis: {joint_type: prismatic}\nname: \xe9t\xe9\n")
        rows = [f"{0.01 * i!r},{i},{i}" for i in range(300)]
        big = d / "bigcell.csv"
        big.write_text("t,q,f\n" + "\n".join(rows[:7] + ["0.07," + "9" * 10_000_000 + ",7"] + rows[8:]))
        neg = d / "negative.csv"
        neg.write_text("t,q,f\n" + "\n".join(f"{0.01 * i - 1.0!r},{i},{i}" for i in range(300)))
        duph = d / "duphead.csv"
        duph.write_text("t,q,q\n" + "\n".join(rows))
        short = axis_bag(d / "short", keep=lambda t: np.arange(t.size) < 120)
        zero = axis_bag(d / "zero", effort=lambda e: 0.0 * e)
        imp = ["--plant", "axis", "--map", "time=t,position=q,effort=f", "--description", DESC]
        cli_cases = [
            ("compare on 120 samples", ["compare", short]),
            ("all-zero effort, compare", ["compare", zero]),
            ("all-zero effort, report", ["report", zero, "-o", d / "rep"]),
            ("--cutoff 1e-9", ["compare", EMPS, "--cutoff", "1e-9"]),
            ("--cutoff abc", ["compare", EMPS, "--cutoff", "abc"]),
            ("--segments 2.5", ["compare", EMPS, "--segments", "2.5"]),
            ("batch --workers 0", ["batch", EMPS, "-o", d / "fleet", "--workers", "0"]),
            ("--fix of every parameter (M=2,Fv=1)", ["identify", EMPS, "--fix", "M=2,Fv=1", "--json"]),
            ("--fix M twice", ["identify", EMPS, "--fix", "M=1,M=2"]),
            ("description inertia: 2e3 (YAML 1.2 number)", ["identify", EMPS, "--description", e2e3, "--json"]),
            ("description with a duplicated key", ["compare", EMPS, "--description", dup]),
            ("description not UTF-8", ["compare", EMPS, "--description", latin]),
            ("pulley_radius: 100", ["compare", CDPR, "--description", big_pulley]),
            ("CSV with one 10 MB cell", ["import", big, *imp, "-o", d / "i1"]),
            ("CSV with negative times", ["import", neg, *imp, "-o", d / "i2"]),
            ("CSV with a duplicated header", ["import", duph, *imp, "-o", d / "i3"]),
        ]
        node_cases = [
            ("cdpr sim, timestep only", "cable_sim_node", "sim", "cdpr", ["timestep:=0.001"]),
            ("cdpr sim, integer rate", "cable_sim_node", "sim", "cdpr", ["rate:=100"]),
            ("axis sim, integer inertia", "cable_sim_node", "sim", "axis", ["inertia:=2"]),
            ("cdpr sim, rate 0", "cable_sim_node", "sim", "cdpr", ["rate:=0.0"]),
            ("cdpr sim, seed -1", "cable_sim_node", "sim", "cdpr", ["seed:=-1"]),
            ("cdpr sim, payload_mass -500", "cable_sim_node", "sim", "cdpr", ["payload_mass:=-500.0"]),
            ("cdpr sim, tension_noise -5", "cable_sim_node", "sim", "cdpr", ["tension_noise:=-5.0"]),
            ("cdpr sim, 1-element payload_com", "cable_sim_node", "sim", "cdpr", ["payload_com:=[0.1]"]),
            ("cdpr sim, list mixing integers and numbers", "cable_sim_node", "sim", "cdpr",
             ["payload_com:=[0, 0.5, 1]"]),
            ("crane controller, 2 gains", "pd_feedforward", "controller", "crane", ["kp:=[1.0, 2.0]"]),
            ("leg controller, unknown mode", "pd_feedforward", "controller", "leg", ["mode:=fast"]),
        ]
        print("| case | command | exit | stderr line / result |")
        print("|---|---|---|---|")
        for name, argv in cli_cases:
            code, out, err = run(argv)
            if code == 0:
                try:
                    js = json.loads(out)
                    what = "; ".join(js.get("warnings", [])) or "(no warning)"
                    if "M" in js.get("params", {}):
                        what += f" -> M = {js['params']['M']['value']:.4g} from {js['samples']} samples"
                except ValueError:
                    what = out.strip().splitlines()[0] if out.strip() else ""
            else:
                what = err.strip()
            what = what.replace(str(d) + "/", "").replace(str(REPO) + "/", "").replace("|", "\\|")
            cmd = "cablelab " + " ".join(str(a).replace(str(d) + "/", "").replace(str(REPO) + "/", "")
                                         for a in argv)
            print(f"| {name} | `{cmd[:140]}` | {code} | {what} |")
        for name, package, role, plant, params in node_cases:
            argv = ["--plant", plant, "--ros-args"]
            for p in params + (["duration:=0.05"] if role == "sim" and plant == "cdpr" else []):
                argv += ["-p", p]
            if role == "sim" and plant == "axis":
                code, err = run_node_check(package, role, plant, params)
            else:
                code, err = run_node_main(package, role, argv)
            lines = [ln for ln in err.splitlines() if ln.strip() and not ln.startswith("[")]
            what = lines[-1] if lines else "(runs)"
            cmd = f"{package} --plant {plant} --ros-args " + " ".join(f"-p {p}" for p in params)
            print(f"| {name} | `{cmd}` | {code} | {what.replace('|', chr(92) + '|')} |")
    finally:
        shutil.rmtree(d, ignore_errors=True)
    return 0


def run_node_check(package, role, plant, params):
    """A node that runs until stopped: built (parameters declared and checked) and destroyed."""
    import rclpy

    from cablelab.errors import CablelabError
    from cablelab.ros.launch import release_domain_id, reserve_domain_id
    from cablelab.ros.runner import node_module

    dom = reserve_domain_id(salt=4445)
    args = ["x", "--ros-args"]
    for p in params:
        args += ["-p", p]
    rclpy.init(args=args, domain_id=dom)
    try:
        node_module(plant, role).make_node().destroy_node()
        return 0, "(node built: parameters declared and checked)"
    except CablelabError as exc:
        return 2, f"{package} --plant {plant}: error: {exc}"
    finally:
        rclpy.try_shutdown()
        release_domain_id(dom)

if __name__ == "__main__":
    sys.exit(main())
