"""``./run``'s first use builds .venv quietly: pip's output (setuptools banners that look like
errors) goes to .venv/pip.log, shown (its tail) only when the build fails. Checked on a copy of the
script with a stand-in Python whose "pip" prints such a banner, so no network and no real build."""
from __future__ import annotations

import os
import shutil
import subprocess

import pytest

from robust_helpers import REPO

BANNER = "!! ******** Please be careful with folders in your working directory ********"

FAKE_PYTHON = f"""#!/bin/bash
# stand-in for python3.11: passes the version check, makes a venv whose python is a fake pip
if [ "$1" = "-c" ]; then exit 0; fi
if [ "$1" = "-m" ] && [ "$2" = "venv" ]; then
  mkdir -p "$3/bin"
  cat > "$3/bin/python" <<'EOF'
#!/bin/bash
echo "{BANNER}" >&2
echo "pip $*"
exit ${{FAKE_PIP_RC:-0}}
EOF
  chmod +x "$3/bin/python"; exit 0
fi
exit 1
"""


@pytest.fixture
def project(tmp_path):
    """A directory with ./run, its requirement files and one package, and a PATH whose only
    python3.11 is the stand-in."""
    root = tmp_path / "proj"
    (root / "src" / "pkg").mkdir(parents=True)
    shutil.copy(REPO / "run", root / "run")
    for name in ("requirements.txt", "constraints.txt", "src/pkg/setup.py", "src/pkg/setup.cfg"):
        (root / name).write_text("# test\n")
    fake = tmp_path / "bin"
    fake.mkdir()
    (fake / "python3.11").write_text(FAKE_PYTHON)
    (fake / "python3.11").chmod(0o755)
    env = {"PATH": f"{fake}:/usr/bin:/bin", "HOME": str(tmp_path), "LANG": "C.UTF-8"}
    return root, env


def _run(root, env, *args, **extra):
    return subprocess.run([str(root / "run"), *args], cwd=root, env={**env, **extra},
                          capture_output=True, text=True, timeout=120)


def test_first_use_is_quiet_and_logs_pip(project):
    root, env = project
    res = _run(root, env, "true")
    assert res.returncode == 0, res.stderr
    assert BANNER not in res.stderr and BANNER not in res.stdout
    assert len(res.stderr.splitlines()) <= 2, res.stderr            # "creating ...", "ready ..."
    log = (root / ".venv" / "pip.log").read_text()
    assert log.count(BANNER) == 4 and "pip -m pip install" in log   # all three pip calls logged,
    assert "-m cablelab.native" in log                               # and the compiled paths' build
    assert (root / ".venv" / ".stamp").is_file()
    again = _run(root, env, "true")                                  # built: nothing printed
    assert again.returncode == 0 and again.stderr == "" and again.stdout == ""


def test_failed_build_shows_the_log_tail_and_fails(project):
    root, env = project
    res = _run(root, env, "true", FAKE_PIP_RC="1")
    assert res.returncode != 0
    assert BANNER in res.stderr and "pip.log" in res.stderr and "failed" in res.stderr
    assert not (root / ".venv" / ".stamp").exists()                 # the next call rebuilds
    res = _run(root, env, "true")
    assert res.returncode == 0 and (root / ".venv" / ".stamp").is_file(), res.stderr


def test_command_and_its_arguments_run_unchanged(project):
    root, env = project
    res = _run(root, env, "sh", "-c", 'echo "$0 $1"; exit 3', "a b", "c")
    assert res.returncode == 3 and res.stdout == "a b c\n"
    assert os.access(root / "run", os.X_OK)
    usage = _run(root, env)                               # no command: the header, whole
    assert usage.returncode == 0 and usage.stdout.startswith("cablelab's one entry point.")
    assert usage.stdout.rstrip().endswith("when those files change).") and "set -e" not in usage.stdout
