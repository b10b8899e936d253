"""Data loss at output targets: ``--overwrite`` replaces only what a cablelab verb wrote (the
``.cablelab-output`` marker), never a user's file or directory, never an input (a ``.mcap`` file
stands for its bag directory); ``batch -o OUT`` is neither ROOT nor nested with it and never
takes over a user's directory; two writers of one output are refused by a lock."""
from __future__ import annotations

import os
import shutil
import subprocess
import sys
import tempfile
import textwrap
from pathlib import Path

import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from robust_helpers import CDPR, EMPS, REPO, tree_snapshot

from cablelab.atomic import MARKER, marker_of

IMPORT_DESC = "{plant: axis, axis: {joint_type: prismatic}}"
FUZZ = settings(max_examples=int(os.environ.get("CABLELAB_FUZZ_EXAMPLES", "12")), deadline=None,
                derandomize=not os.environ.get("CABLELAB_FUZZ_RANDOM"),
                suppress_health_check=[HealthCheck.function_scoped_fixture, HealthCheck.too_slow])


def _csv(path, rows=200):
    path.write_text("t,q,f\n" + "".join(f"{0.001 * i:.3f},{0.01 * i:.4f},{(i % 7) - 3.0}\n"
                                         for i in range(rows)))
    return path


def _verb_args(verb, src_dir, out):
    """argv of a writing verb whose output is ``out`` (inputs under ``src_dir``)."""
    if verb == "import":
        return ["import", _csv(Path(src_dir) / "a.csv"), "--plant", "axis", "--map",
                "time=t,position=q,effort=f", "--description", IMPORT_DESC, "-o", out]
    if verb == "repair":
        return ["repair", EMPS, "-o", out]
    if verb == "estimate":
        return ["estimate", CDPR, "--out", out, "--json"]
    return ["report", EMPS, "-o", out, "--folds", "2"]


def _refused(res, *words):
    assert res.code == 2, (res.code, res.out, res.err)
    assert len(res.err_lines) == 1 and "Traceback" not in res.err, res.err
    for w in words:
        assert w in res.err, (w, res.err)


def _no_litter(directory):
    return [p.name for p in Path(directory).iterdir()
            if ".partial-" in p.name or ".old-" in p.name or p.name.endswith(".lock")]


# ----------------------------------------------------------------------------- the marker rule
@pytest.mark.parametrize("verb", ["report", "import", "repair", "estimate"])
def test_overwrite_never_deletes_a_user_directory(cli, tmp_path, verb):
    """`report BAG -o mydocs --overwrite` deleted thesis.tex and sub/: now refused, all kept."""
    out = tmp_path / "mydocs"
    (out / "sub").mkdir(parents=True)
    (out / "thesis.tex").write_text("\\chapter{precious}")
    (out / "sub" / "data.csv").write_text("1,2,3")
    before = tree_snapshot(out)
    _refused(cli(*_verb_args(verb, tmp_path, out), "--overwrite"), str(out), "did not write",
             "not replacing")
    assert tree_snapshot(out) == before
    assert _no_litter(tmp_path) == []


@pytest.mark.parametrize("verb", ["report", "import", "repair"])
def test_overwrite_never_replaces_a_file_by_a_directory(cli, tmp_path, verb):
    """`report -o precious.txt --overwrite` replaced the file with a directory: now refused."""
    out = tmp_path / "precious.txt"
    out.write_text("precious")
    _refused(cli(*_verb_args(verb, tmp_path, out), "--overwrite"), str(out), "is a file")
    assert out.is_file() and out.read_text() == "precious"


def test_overwrite_never_follows_a_symlink(cli, tmp_path):
    real = tmp_path / "real"
    real.mkdir()
    (real / "keep").write_text("x")
    link = tmp_path / "link"
    link.symlink_to(real)
    _refused(cli(*_verb_args("import", tmp_path, link), "--overwrite"), str(link), "symbolic link")
    assert link.is_symlink() and (real / "keep").read_text() == "x"


@pytest.mark.parametrize("verb", ["import", "repair"])
def test_overwrite_replaces_what_the_verb_wrote(cli, tmp_path, verb):
    """Its own output (marker naming the verb) is replaced; so is an empty directory."""
    out = tmp_path / "out"
    out.mkdir()                                    # empty: nothing to lose
    assert cli(*_verb_args(verb, tmp_path, out), "--overwrite").code == 0
    assert marker_of(out) == verb
    assert cli(*_verb_args(verb, tmp_path, out), "--overwrite").code == 0
    assert marker_of(out) == verb
    from cablelab.bags import open_bag

    assert sum(open_bag(out).counts.values()) > 0
    assert _no_litter(tmp_path) == []


@pytest.mark.parametrize("added", ["notes.txt", "sub/mine.tex"])
def test_overwrite_keeps_what_the_user_added_to_an_output(cli, tmp_path, added):
    """An output the verb wrote, with a file of the user's added since: refused, file kept."""
    out = tmp_path / "out"
    assert cli(*_verb_args("import", tmp_path, out)).code == 0
    (out / added).parent.mkdir(exist_ok=True)
    (out / added).write_text("mine")
    before = tree_snapshot(out)
    _refused(cli(*_verb_args("import", tmp_path, out), "--overwrite"), str(out), "did not write",
             added.split("/")[0])
    assert tree_snapshot(out) == before
    (out / added).unlink()           # taken away again: the output is the verb's own once more
    if "/" in added:
        (out / added).parent.rmdir()
    assert cli(*_verb_args("import", tmp_path, out), "--overwrite").code == 0


def test_a_bag_of_another_recorder_is_not_replaced(cli, tmp_path):
    """A copy of a shipped bag (no marker: ros2 bag record wrote it) is the user's data."""
    out = tmp_path / "theirs"
    shutil.copytree(EMPS, out)
    assert not (out / MARKER).exists()
    before = tree_snapshot(out)
    _refused(cli(*_verb_args("import", tmp_path, out), "--overwrite"), str(out), MARKER)
    assert tree_snapshot(out) == before


def test_bag_writer_replaces_only_marked_bags(tmp_path):
    from cablelab.bags import BagWriter
    from cablelab.errors import CablelabError

    with BagWriter(tmp_path / "b") as w:
        w.write_clock([1.0, 2.0])
    assert marker_of(tmp_path / "b") == "bag"
    with BagWriter(tmp_path / "b", overwrite=True) as w:
        w.write_clock([1.0])
    shutil.copytree(EMPS, tmp_path / "theirs")
    with pytest.raises(CablelabError, match="not a bag cablelab wrote"):
        BagWriter(tmp_path / "theirs", overwrite=True)
    assert (tmp_path / "theirs" / "emps.mcap").exists()


@pytest.mark.parametrize("verb", ["report", "repair", "estimate"])
def test_output_inside_the_bag_of_an_mcap_input_is_refused(cli, tmp_path, verb):
    """`report BAG/x.mcap -o BAG/rep`: the input bag is the directory holding the .mcap."""
    bag = tmp_path / "bag"
    shutil.copytree(CDPR if verb == "estimate" else EMPS, bag)
    mcap = next(bag.glob("*.mcap"))
    before = tree_snapshot(bag)
    args = _verb_args(verb, tmp_path, bag / "rep")
    args[1] = mcap
    _refused(cli(*args), "input")
    assert tree_snapshot(bag) == before


def test_mcap_beside_unrelated_files_is_only_itself(tmp_path):
    """An .mcap lying in a folder of other things does not make that folder an input."""
    from cablelab.atomic import check_target, input_paths, release_target

    shutil.copy(next(EMPS.glob("*.mcap")), tmp_path / "x.mcap")
    (tmp_path / "notes.txt").write_text("x")
    assert input_paths(tmp_path / "x.mcap") == [tmp_path / "x.mcap"]
    check_target(tmp_path / "rep", inputs=[tmp_path / "x.mcap"])
    release_target(tmp_path / "rep")


# ----------------------------------------------------------------------------- hypothesis
_names = st.text(alphabet="abcdefgh_.0123456789", min_size=1, max_size=8).filter(
    lambda s: s not in (".", "..", MARKER))
_tree = st.recursive(st.binary(max_size=64),
                     lambda kids: st.dictionaries(_names, kids, min_size=1, max_size=4), max_leaves=10)


def _make(path: Path, node) -> None:
    if isinstance(node, bytes):
        path.write_bytes(node)
    else:
        path.mkdir()
        for name, kid in node.items():
            _make(path / name, kid)


@FUZZ
@given(tree=st.one_of(st.just({}), _tree), verb=st.sampled_from(["import", "repair"]),
       inside_output=st.booleans())
def test_fuzz_overwrite_never_deletes_what_the_verb_did_not_write(cli, tree, verb, inside_output):
    """Random trees of user files at the target, or added inside an output the verb wrote:
    --overwrite refuses (or, for an empty directory, replaces) and no byte the verb did not
    write is lost."""
    with tempfile.TemporaryDirectory() as d:
        out = Path(d) / "target"
        if inside_output and isinstance(tree, dict):
            assert cli(*_verb_args(verb, d, out)).code == 0
            for name, kid in tree.items():
                if not (out / name).exists():
                    _make(out / name, kid)
        else:
            _make(out, tree)
        before = tree_snapshot(out)
        res = cli(*_verb_args(verb, d, out), "--overwrite")
        if tree == {}:
            assert res.code == 0, res.err          # an empty directory holds nothing to lose
        else:
            assert res.code == 2 and "not replacing" in res.err, res.err
            assert tree_snapshot(out) == before
        assert _no_litter(d) == []


# ----------------------------------------------------------------------------- batch OUT
@pytest.fixture
def fleet_root(tmp_path):
    root = tmp_path / "fleet"
    root.mkdir()
    shutil.copytree(EMPS, root / "emps")
    return root


@pytest.mark.parametrize("where", ["same", "inside", "contains"])
def test_batch_out_nested_with_root_is_refused(cli, fleet_root, where):
    out = {"same": fleet_root, "inside": fleet_root / "out", "contains": fleet_root.parent}[where]
    before = tree_snapshot(fleet_root)
    _refused(cli("batch", fleet_root, "-o", out), "input")
    assert tree_snapshot(fleet_root) == before


def test_batch_never_takes_over_a_user_directory(cli, fleet_root, tmp_path):
    """A user's OUT/index.html (no marker) is not replaced: the run is refused."""
    out = tmp_path / "site"
    out.mkdir()
    (out / "index.html").write_text("<h1>my own page</h1>")
    _refused(cli("batch", fleet_root, "-o", out), str(out), "did not write")
    assert (out / "index.html").read_text() == "<h1>my own page</h1>"
    assert sorted(p.name for p in out.iterdir()) == ["index.html"]


def test_batch_claims_its_out_and_resumes(tmp_path):
    """The claim marks OUT (batch), a second claim of the same OUT (resume) is accepted."""
    from cablelab.atomic import claim_output_dir, release_target

    out = tmp_path / "a" / "out"
    assert claim_output_dir(out, inputs=[tmp_path / "fleet"], verb="batch") is True
    assert marker_of(out) == "batch"
    (out / "results.parquet").mkdir()
    release_target(out)
    assert claim_output_dir(out, inputs=[tmp_path / "fleet"], verb="batch") is True
    release_target(out)
    assert _no_litter(out.parent) == []


# ----------------------------------------------------------------------------- one writer
HOLDER = textwrap.dedent("""
    import sys, time
    from cablelab.atomic import {fn}
    {fn}(sys.argv[1]{extra})
    print("locked", flush=True)
    time.sleep(120)
""")


def _hold(path, fn="lock_target", extra=""):
    p = subprocess.Popen([sys.executable, "-c", HOLDER.format(fn=fn, extra=extra), str(path)],
                         stdout=subprocess.PIPE, text=True, cwd=REPO)
    assert p.stdout.readline().strip() == "locked"
    return p


@pytest.mark.parametrize("verb", ["report", "import", "repair", "estimate"])
def test_second_writer_of_one_output_is_refused(cli, tmp_path, verb):
    out = tmp_path / "out"
    holder = _hold(out)
    try:
        _refused(cli(*_verb_args(verb, tmp_path, out), "--overwrite"), str(out),
                 f"is being written by another cablelab process (pid {holder.pid})")
    finally:
        holder.kill()
        holder.wait()
    assert not out.exists()
    # the holder died (its lock with it): the next writer goes ahead
    if verb == "import":
        assert cli(*_verb_args(verb, tmp_path, out)).code == 0
        assert _no_litter(tmp_path) == []


def test_second_batch_into_one_out_is_refused(cli, fleet_root, tmp_path):
    out = tmp_path / "out"
    holder = _hold(out, "claim_output_dir", ", verb='batch'")
    try:
        _refused(cli("batch", fleet_root, "-o", out), f"another cablelab process (pid {holder.pid})")
    finally:
        holder.kill()
        holder.wait()
    assert sorted(p.name for p in out.iterdir()) == [MARKER]


def test_two_concurrent_cli_writers(tmp_path):
    """Two real `cablelab import -o same` processes started together: exactly one writes (exit
    0), the other exits 2 naming the lock, or waits for nothing and finds the output there."""
    src = _csv(tmp_path / "a.csv", rows=20000)
    out = tmp_path / "out"
    argv = [str(REPO / "run"), "cablelab", "import", str(src), "--plant", "axis", "--map",
            "time=t,position=q,effort=f", "--description", IMPORT_DESC, "-o", str(out)]
    procs = [subprocess.Popen(argv, stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True)
             for _ in range(2)]
    results = [(p.wait(timeout=300), p.stderr.read()) for p in procs]
    codes = sorted(c for c, _ in results)
    assert codes == [0, 2], results
    err = [e for c, e in results if c == 2][0]
    assert "being written by another cablelab process" in err or "exists already" in err, err
    from cablelab.bags import open_bag

    assert open_bag(out).counts["/axis/joint_states"] == 20000


def test_stale_lock_file_of_a_killed_writer_does_not_block(cli, tmp_path):
    out = tmp_path / "out"
    (tmp_path / ".out.lock").write_text("999999\n")   # left by a SIGKILLed run: no flock on it
    assert cli(*_verb_args("import", tmp_path, out)).code == 0
    assert _no_litter(tmp_path) == []


def test_a_verb_failing_after_its_check_leaves_no_lock(cli, tmp_path):
    """The lock is taken before the work; a verb failing in the work leaves no lock file and
    holds nothing (the next writer, in this same process or another, goes ahead)."""
    out = tmp_path / "rep"
    res = cli("report", EMPS, "-o", out, "--effects", "no_such_effect")
    assert res.code == 2 and "no_such_effect" in res.err, res.err
    assert list(tmp_path.iterdir()) == []
    from cablelab.atomic import _HELD

    assert _HELD == {}


def test_repair_default_output_of_a_bag_mcap_is_beside_the_bag(cli, tmp_path):
    """`repair run/run.mcap` writes run_repaired next to the bag, never inside it."""
    bag = tmp_path / "run"
    shutil.copytree(EMPS, bag)
    before = tree_snapshot(bag)
    res = cli("repair", bag / "emps.mcap")
    assert res.code == 0, res.err
    assert (tmp_path / "run_repaired" / "metadata.yaml").exists()
    assert tree_snapshot(bag) == before


def test_batch_never_writes_into_another_verbs_output(cli, fleet_root, tmp_path):
    out = tmp_path / "rep"
    assert cli(*_verb_args("import", tmp_path, out)).code == 0
    before = tree_snapshot(out)
    _refused(cli("batch", fleet_root, "-o", out), "is the output of cablelab import")
    assert tree_snapshot(out) == before
