"""No verb overwrites without --overwrite, none writes into its input, outputs appear whole or
not at all: a full disk (96 KiB tmpfs, or ENOSPC injected), a read-only file system and a failure
part-way leave no partial output, the old output intact and a one-line error."""
from __future__ import annotations

import errno
import json
import os
import subprocess
import sys
import time

import pytest

from robust_helpers import CDPR, EMPS, REPO, tree_snapshot

IMPORT_DESC = "{plant: axis, axis: {joint_type: prismatic}}"


def _csv(path, rows=400, bad=None):
    lines = ["t,q,f"] + [f"{0.001 * i:.3f},{0.01 * i:.4f},{(i % 7) - 3.0}" for i in range(rows)]
    if bad is not None:
        i, cell = bad
        parts = lines[i].split(",")
        parts[1] = cell
        lines[i] = ",".join(parts)
    path.write_text("\n".join(lines) + "\n")
    return path


def _import(cli, src, out, *extra):
    return cli("import", src, "--plant", "axis", "--map", "time=t,position=q,effort=f",
               "--description", IMPORT_DESC, "-o", out, *extra)


def _one_line_error(res, *words):
    assert res.code == 2, (res.code, res.out, res.err)
    assert len(res.err_lines) == 1 and "Traceback" not in res.err, res.err
    for w in words:
        assert w in res.err, (w, res.err)


def _no_partials(directory):
    return [p.name for p in directory.iterdir() if ".partial-" in p.name or ".old-" in p.name]


# ----------------------------------------------------------------------------- overwrite / input
@pytest.mark.parametrize("verb", ["estimate", "report", "import", "repair"])
def test_existing_output_needs_overwrite(cli, tmp_path, verb):
    out = tmp_path / "out"
    out.mkdir()
    (out / "keep.txt").write_text("precious")
    if verb == "estimate":
        res = cli("estimate", CDPR, "--out", out, "--json")
    elif verb == "report":
        res = cli("report", EMPS, "-o", out, "--folds", "2")
    elif verb == "import":
        res = _import(cli, _csv(tmp_path / "a.csv"), out)
    else:
        res = cli("repair", EMPS, "-o", out)
    _one_line_error(res, str(out), "exists already", "--overwrite")
    assert (out / "keep.txt").read_text() == "precious"


def test_every_writing_verb_has_overwrite(cli):
    for verb in ("estimate", "report", "import", "record", "repair"):
        res = cli(verb, "--help")
        assert res.code == 0 and "--overwrite" in res.out, verb


@pytest.mark.parametrize("target", ["same", "inside"])
@pytest.mark.parametrize("verb", ["estimate", "report", "repair"])
def test_never_writes_into_its_input(cli, tmp_path, verb, target):
    import shutil

    bag = tmp_path / "bag"
    shutil.copytree(CDPR if verb == "estimate" else EMPS, bag)
    before = tree_snapshot(bag)
    out = bag if target == "same" else bag / "sub"
    opt = "--out" if verb == "estimate" else "-o"
    args = [verb, bag, opt, out, "--overwrite"] + (["--folds", "2"] if verb == "report" else [])
    _one_line_error(cli(*args), "input")
    assert tree_snapshot(bag) == before


def test_overwrite_replaces_whole_output(cli, tmp_path):
    out = tmp_path / "bag"
    src = _csv(tmp_path / "a.csv", rows=300)
    assert _import(cli, src, out).code == 0
    assert _import(cli, _csv(tmp_path / "b.csv", rows=500), out, "--overwrite", "--json").code == 0
    from cablelab.bags import open_bag

    assert open_bag(out).counts["/axis/joint_states"] == 500
    assert _no_partials(tmp_path) == []


# ----------------------------------------------------------------------------- full disk
def test_full_disk_leaves_nothing(cli, tiny_fs):
    """CDPR estimates (~470 kB) into a 96 KiB file system: one line, no output, no temporary."""
    out = tiny_fs / "est"
    _one_line_error(cli("estimate", CDPR, "--out", out), "no space left on device", str(out))
    assert list(tiny_fs.iterdir()) == []


def test_full_disk_report_and_import(cli, tiny_fs, tmp_path):
    _one_line_error(cli("report", EMPS, "-o", tiny_fs / "rep", "--folds", "2"), "no space left")
    assert list(tiny_fs.iterdir()) == []
    _one_line_error(_import(cli, _csv(tmp_path / "big.csv", rows=20000), tiny_fs / "imp"), "no space left")
    assert list(tiny_fs.iterdir()) == []


def test_full_disk_keeps_old_output(cli, tmp_path, monkeypatch):
    """ENOSPC injected part-way through writing (any file system): the previous output stays."""
    out = tmp_path / "bag"
    assert _import(cli, _csv(tmp_path / "a.csv", rows=300), out).code == 0
    before = tree_snapshot(out)
    from cablelab.bags import writer

    real = writer.BagWriter.write_joint_states

    def boom(self, *a, **k):
        real(self, *a, **k)
        raise OSError(errno.ENOSPC, "No space left on device")
    monkeypatch.setattr(writer.BagWriter, "write_joint_states", boom)
    _one_line_error(_import(cli, _csv(tmp_path / "b.csv", rows=500), out, "--overwrite"), "no space left")
    assert tree_snapshot(out) == before
    assert _no_partials(tmp_path) == []


# ----------------------------------------------------------------------------- read-only
@pytest.mark.parametrize("verb", ["estimate", "report", "import", "record", "repair"])
def test_read_only_target(cli, ro_fs, tmp_path, verb):
    out = ro_fs / "out"
    if verb == "estimate":
        res = cli("estimate", CDPR, "--out", out)
    elif verb == "report":
        res = cli("report", EMPS, "-o", out, "--folds", "2")
    elif verb == "import":
        res = _import(cli, _csv(tmp_path / "a.csv"), out)
    elif verb == "record":
        res = cli("record", "-o", out, "--plant", "axis", "--duration", "1")
    else:
        res = cli("repair", EMPS, "-o", out)
    _one_line_error(res, str(out))
    assert "not writable" in res.err or "read-only" in res.err
    assert list(ro_fs.iterdir()) == []


# ----------------------------------------------------------------------------- kill part-way
def test_kill_during_report_leaves_no_output(tmp_path):
    """SIGKILL while the report is being written: DIR never exists (only a hidden temporary)."""
    out = tmp_path / "rep"
    proc = subprocess.Popen([sys.executable, "-m", "cablelab.cli", "report", str(EMPS), "-o", str(out),
                             "--folds", "2"], stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)
    deadline = time.monotonic() + 120
    while time.monotonic() < deadline and not any(".partial-" in p.name for p in tmp_path.iterdir()):
        if proc.poll() is not None:
            pytest.skip("report finished before it could be killed")
        time.sleep(0.02)
    proc.kill()
    proc.wait(30)
    assert not out.exists()


def test_import_text_cell_is_an_error(cli, tmp_path):
    res = _import(cli, _csv(tmp_path / "a.csv", bad=(17, "abc")), tmp_path / "out")
    _one_line_error(res, "row 18", "'q'", "'abc'", "not a number")
    assert not (tmp_path / "out").exists()


def test_import_empty_cells_are_counted(cli, tmp_path):
    res = _import(cli, _csv(tmp_path / "a.csv", bad=(17, "")), tmp_path / "out", "--json")
    assert res.code == 0, res.err
    out = json.loads(res.out)
    assert out["warnings"] == [f"{tmp_path / 'a.csv'}: 1 of 400 samples have no finite position value "
                               f"(missing cells)"]


def test_import_refuses_ms_time_column_and_reports_gaps(cli, tmp_path):
    rows = 400
    ms = tmp_path / "ms.csv"
    ms.write_text("t,q,f\n" + "\n".join(f"{i},{0.01 * i},{i % 5}" for i in range(rows)) + "\n")
    res = _import(cli, ms, tmp_path / "out")
    _one_line_error(res, "milliseconds", "--map time=0.001*")
    assert not (tmp_path / "out").exists()
    gap = tmp_path / "gap.csv"
    t = [0.001 * i for i in range(rows)]
    t = t[:200] + [x + 1.0 for x in t[200:]]
    gap.write_text("t,q,f\n" + "\n".join(f"{x:.3f},{0.01 * i},{i % 5}" for i, x in enumerate(t)) + "\n")
    res = _import(cli, gap, tmp_path / "out2", "--json")
    assert res.code == 0, res.err
    w = json.loads(res.out)["warnings"]
    assert len(w) == 1 and "1 recording gap" in w[0] and "1 s" in w[0], w
