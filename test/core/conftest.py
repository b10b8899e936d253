"""Fixtures of the robustness tests: the CLI in-process, tiny and read-only file systems (tmpfs,
root only). The helpers they use are in robust_helpers.py (a unique module name: test files
import it, never ``conftest``)."""
from __future__ import annotations

import sys
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parent))

from robust_helpers import cli, ro_fs, tiny_fs  # noqa: E402,F401  (fixtures)
