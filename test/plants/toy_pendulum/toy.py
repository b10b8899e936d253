"""The toy plant as its author would have it: what ``cablelab new-plant pendulum`` writes, with the
pendulum's own law laid over it (the files under ``law/``: its description section, effects,
MuJoCo model, nominal model, docs, data and tests). Nothing else of the package is kept in the
repository, so the toy cannot drift from the template."""
from __future__ import annotations

import shutil
import tempfile
from functools import lru_cache
from pathlib import Path

from cablelab.plant_template import plant_files

LAW = Path(__file__).resolve().parent / "law"


def build(dest: Path) -> Path:
    """Write the toy plant into ``dest`` (the template, then the law files over it); ``dest``
    gets ``pendulum_plant/`` and ``test_pendulum_plant.py``. Returns ``dest``."""
    dest = Path(dest)
    for rel, text in plant_files("pendulum").items():
        if rel == "pyproject.toml":      # not installed: the tests announce its entry point
            continue
        path = dest / rel
        path.parent.mkdir(parents=True, exist_ok=True)
        path.write_text(text)
    for src in LAW.rglob("*"):
        if src.is_file() and "__pycache__" not in src.parts:
            target = dest / src.relative_to(LAW)
            target.parent.mkdir(parents=True, exist_ok=True)
            shutil.copyfile(src, target)
    return dest


@lru_cache(maxsize=None)
def toy_dir() -> Path:
    """The toy plant built once per test process (a temporary directory)."""
    return build(Path(tempfile.mkdtemp(prefix="cablelab-toy-")))
