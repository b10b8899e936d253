"""Run the hostile cases of issue 14 through ``cablelab.cli.main`` (in-process) and print the
markdown table of docs/robustness.md: case, command, exit status, the one stderr line or the
warnings (nothing here is written by hand). A second table, the numeric-validation cases (ROS
parameters of the nodes, numeric options, description numbers, CSV cells), follows it.

    ./run python bench/robustness_table.py              # both tables
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


def main() -> int:
    if "--validation" not in sys.argv[1:]:
        main_issue14()
        print()
    return validation_table()


def main_issue14() -> int:
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
            code, out, err = run(argv)
            if code == 0:
                try:
                    js = json.loads(out)
                    what = "; ".join(js.get("warnings", [])) or "(no warning)"
                    if "M" in js.get("params", {}):
                        what += f" -> M = {js['params']['M']['value']:.2f} kg from {js['samples']} samples"
                except ValueError:
                    what = out.strip().splitlines()[0] if out.strip() else ""
            else:
                what = err.strip()
            what = what.replace(str(d) + "/", "").replace(str(REPO) + "/", "").replace("|", "\\|")
            cmd = "cablelab " + " ".join(str(a).replace(str(d) + "/", "").replace(str(REPO) + "/", "")
                                         for a in argv)
            print(f"| {name} | `{cmd}` | {code} | {what} |")
    finally:
        shutil.rmtree(d, ignore_errors=True)
    return 0


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
        node_module(plant, role).make_node(None).destroy_node()
        return 0, "(node built: parameters declared and checked)"
    except CablelabError as exc:
        return 2, f"{package} --plant {plant}: error: {exc}"
    finally:
        rclpy.try_shutdown()
        release_domain_id(dom)


if __name__ == "__main__":
    sys.exit(main())
