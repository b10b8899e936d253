"""Helpers of the robustness tests (test/core): hostile copies of the shipped bags, snapshots of
inputs, the in-process CLI result. Fixtures using them are in conftest.py."""
from __future__ import annotations

import functools
import os
import subprocess
import uuid
from pathlib import Path

import numpy as np
import pytest

REPO = Path(__file__).resolve().parents[2]


@functools.lru_cache(maxsize=None)
def toy_plant_dir() -> Path:
    """The toy plant (test/plants/toy_pendulum: the template plus its law) built once per process;
    the directory holds ``pendulum_plant/``."""
    import importlib.util

    spec = importlib.util.spec_from_file_location(
        "cablelab_toy_builder", REPO / "test" / "plants" / "toy_pendulum" / "toy.py")
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    return module.toy_dir()
EMPS = REPO / "bags" / "emps"
CDPR = REPO / "bags" / "cdpr_m1_reference"


class CliResult:
    def __init__(self, code, out, err):
        self.code, self.out, self.err = code, out, err

    @property
    def err_lines(self) -> list[str]:
        """stderr lines, without the progress lines long work prints (``[diagnose] 2/5 ... ETA``)."""
        return [ln for ln in self.err.splitlines()
                if ln.strip() and not (ln.startswith("[") and " ETA " in ln)]


@pytest.fixture
def cli(capsys):
    """``cli("compare", BAG, "--json")`` -> CliResult(code, stdout, stderr) via cablelab.cli.main
    (in-process: an uncaught exception fails the test with its traceback)."""
    from cablelab.cli import main

    def run(*argv) -> CliResult:
        capsys.readouterr()
        try:
            code = main([str(a) for a in argv])
        except SystemExit as exc:    # argparse usage errors
            code = exc.code
        out = capsys.readouterr()
        return CliResult(code, out.out, out.err)

    return run


def copy_bag(src, dst, skip=(), edit=None):
    """Copy every topic of ``src`` to a new bag ``dst`` byte for byte except the ``skip`` ones;
    ``edit(bag, writer)`` then writes replacements. Returns ``dst``."""
    from cablelab.bags import BagWriter, open_bag

    bag = open_bag(src)
    with BagWriter(dst) as w:
        for topic, msgtype in bag.topics.items():
            if topic in skip:
                continue
            w.add_topic(topic, msgtype, transient_local=topic == "/plant_description")
            t_ns, raws = bag.raw(topic)
            for t, r in zip(t_ns.tolist(), raws):
                w.write_raw(topic, t, r)
        if edit is not None:
            edit(bag, w)
    return Path(dst)


def axis_bag(dst, stamps=None, keep=None, log=None, effort=None, position=None):
    """The EMPS drive recording with modified header stamps / kept rows / log times / values."""
    from cablelab.bags import BagWriter, open_bag

    bag = open_bag(EMPS)
    js = bag.joint_state("/axis/joint_states")
    t = js.t if stamps is None else np.asarray(stamps(js.t.copy()))
    k = np.ones(t.size, bool) if keep is None else keep(js.t)
    pos = js.position if position is None else position(js.position.copy())
    eff = js.effort if effort is None else effort(js.effort.copy())
    kw = {} if log is None else {"log_time": log(js.t.copy())[k]}
    with BagWriter(dst) as w:
        w.write_description(bag.description_yaml, t=float(np.nanmin(t[k])))
        w.write_joint_states("/axis/joint_states", t[k], js.names, pos[k], js.velocity[k], eff[k], **kw)
    return Path(dst)


def tree_snapshot(path) -> dict:
    """{relative path: (size, mtime_ns)} of every file under ``path`` (input-untouched checks)."""
    p = Path(path)
    if p.is_file():
        st = p.stat()
        return {p.name: (st.st_size, st.st_mtime_ns)}
    return {str(f.relative_to(p)): (f.stat().st_size, f.stat().st_mtime_ns)
            for f in sorted(p.rglob("*")) if f.is_file()}


def _mount(opts: str, tmp_path) -> Path:
    if os.geteuid() != 0:
        pytest.skip("mounting a tmpfs needs root")
    mnt = tmp_path / f"mnt-{uuid.uuid4().hex[:6]}"
    mnt.mkdir()
    r = subprocess.run(["mount", "-t", "tmpfs", "-o", opts, "tmpfs", str(mnt)], capture_output=True)
    if r.returncode:
        pytest.skip(f"cannot mount tmpfs: {r.stderr.decode().strip()}")
    return mnt


@pytest.fixture
def tiny_fs(tmp_path):
    """A 96 KiB tmpfs: writes of a bag or report run out of space part-way (ENOSPC)."""
    mnt = _mount("size=96k", tmp_path)
    yield mnt
    subprocess.run(["umount", "-l", str(mnt)], check=False)


@pytest.fixture
def ro_fs(tmp_path):
    """A read-only tmpfs (EROFS even for root)."""
    mnt = _mount("ro,size=64k", tmp_path)
    yield mnt
    subprocess.run(["umount", "-l", str(mnt)], check=False)
