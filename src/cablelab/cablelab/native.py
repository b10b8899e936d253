"""Compiled per-period paths: C sources shipped in ``cablelab/csrc/``, built once per environment
into a shared library that a node loads with :mod:`ctypes`.

The Python path stays the oracle and the fallback: :func:`load` returns ``None`` (and says why,
once, in :func:`unavailable_reason`) when there is no compiler, a build fails, or
``CABLELAB_NATIVE=0`` is set, and the caller keeps its Python code.

The compiler is ``$CC`` if set, else the pinned ``ziglang`` wheel (``python -m ziglang cc``: a C
compiler with its own libc headers, so a fresh machine with Python only can build), else ``cc``.
Headers and libraries come from the installed wheels: ros-jazzy (``<venv>/include``,
``<venv>/lib``) and MuJoCo (its package's ``include`` and ``libmujoco.so``). The library is linked
with run paths to those directories, so in a node's process it binds to the same rcl, rmw and
MuJoCo that rclpy and the ``mujoco`` module already loaded. No libpython: the library is only
loaded into a Python process, whose symbols the wheels' rmw libraries then find.

Builds are cached under ``<venv>/lib/cablelab-native/`` by a hash of the sources, the flags and
the compiler; ``python -m cablelab.native`` builds every source ahead (``./run`` does it when it
creates the environment).
"""
from __future__ import annotations

import ctypes
import hashlib
import importlib.util
import os
import shlex
import shutil
import subprocess
import sys
import tempfile
from pathlib import Path

SOURCES = Path(__file__).resolve().parent / "csrc"

ROS_LIBS = ("rcl", "rmw", "rcutils", "rosidl_runtime_c",
            "sensor_msgs__rosidl_typesupport_c", "sensor_msgs__rosidl_generator_c",
            "std_msgs__rosidl_typesupport_c", "std_msgs__rosidl_generator_c",
            "trajectory_msgs__rosidl_typesupport_c", "trajectory_msgs__rosidl_generator_c",
            "geometry_msgs__rosidl_generator_c", "builtin_interfaces__rosidl_generator_c")

_loaded: dict[str, ctypes.CDLL | None] = {}
_reasons: dict[str, str] = {}


class NativeUnavailable(RuntimeError):
    """No compiled library: no compiler, or the build failed (the message says which)."""


def compiler() -> list[str]:
    """The C compiler command: ``$CC``, else the ziglang wheel, else ``cc``."""
    if os.environ.get("CC"):
        return shlex.split(os.environ["CC"])
    if importlib.util.find_spec("ziglang") is not None:
        return [sys.executable, "-m", "ziglang", "cc"]
    if shutil.which("cc"):
        return ["cc"]
    raise NativeUnavailable("no C compiler: install the pinned ziglang wheel (requirements.txt) or set CC")


def _flags() -> list[str]:
    import mujoco

    venv = Path(sys.prefix)
    inc = venv / "include"
    if not inc.is_dir():
        raise NativeUnavailable(f"no ROS 2 headers in {inc} (the ros-jazzy wheels install them there)")
    mj = Path(mujoco.__file__).resolve().parent
    mjlib = next(iter(sorted(mj.glob("libmujoco.so*"))), None)
    if mjlib is None or not (mj / "include").is_dir():
        raise NativeUnavailable(f"the mujoco package in {mj} has no libmujoco.so or include/")
    return ["-O2", "-fPIC", "-shared", "-std=gnu11",
            *[f"-I{p}" for p in sorted(inc.iterdir()) if p.is_dir()], f"-I{mj / 'include'}",
            f"-I{SOURCES}", f"-L{venv / 'lib'}", f"-Wl,-rpath,{venv / 'lib'}",
            "-Wl,--allow-shlib-undefined", *[f"-l{x}" for x in ROS_LIBS],
            str(mjlib), f"-Wl,-rpath,{mj}", "-lm", "-lpthread"]


def cache_dir() -> Path:
    return Path(sys.prefix) / "lib" / "cablelab-native"


def build(name: str, sources: list[Path] | None = None) -> Path:
    """Compile ``csrc/<name>.c`` (or ``sources``) into a cached shared library; its path.

    Raises :class:`NativeUnavailable` with the compiler's last lines when the build fails."""
    srcs = [Path(s) for s in sources] if sources else [SOURCES / f"{name}.c"]
    for s in srcs:
        if not s.is_file():
            raise NativeUnavailable(f"no C source {s}")
    cc, flags = compiler(), _flags()
    h = hashlib.sha256()
    for part in (*cc, *flags):
        h.update(part.encode())
    for s in sorted(srcs) + sorted(SOURCES.glob("*.h")):
        h.update(s.read_bytes())
    out = cache_dir() / f"{name}-{h.hexdigest()[:16]}.so"
    if out.is_file():
        return out
    out.parent.mkdir(parents=True, exist_ok=True)
    # compile to a temporary name and rename: two processes building at once both end well
    fd, tmp = tempfile.mkstemp(suffix=".so", dir=out.parent)
    os.close(fd)
    cmd = [*cc, "-o", tmp, *map(str, srcs), *flags]
    try:
        r = subprocess.run(cmd, capture_output=True, text=True, timeout=600)
    except FileNotFoundError:
        os.unlink(tmp)
        raise NativeUnavailable(f"C compiler {cc[0]!r} not found: install the pinned ziglang wheel or set CC") from None
    if r.returncode:
        os.unlink(tmp)
        tail = " | ".join(r.stderr.strip().splitlines()[-3:])
        raise NativeUnavailable(f"compiling {', '.join(s.name for s in srcs)} failed: {tail}")
    os.replace(tmp, out)
    return out


def load(name: str) -> ctypes.CDLL | None:
    """The compiled library ``name`` (built on first use), or ``None`` to keep the Python path.

    ``CABLELAB_NATIVE=0`` forces ``None``; the reason for any ``None`` is
    :func:`unavailable_reason`."""
    if name in _loaded:
        return _loaded[name]
    lib = None
    if os.environ.get("CABLELAB_NATIVE", "1") == "0":
        _reasons[name] = "CABLELAB_NATIVE=0"
    else:
        try:
            lib = ctypes.CDLL(str(build(name)))
        except (NativeUnavailable, OSError) as e:
            _reasons[name] = str(e)
    _loaded[name] = lib
    return lib


def unavailable_reason(name: str) -> str | None:
    """Why :func:`load` returned ``None`` for ``name`` (None if it loaded or was not tried)."""
    return _reasons.get(name)


def main(argv: list[str] | None = None) -> int:
    """Build every source in ``csrc/`` ahead of first use; one line per library."""
    rc = 0
    for src in sorted(SOURCES.glob("*.c")):
        try:
            print(f"cablelab.native: {src.stem}: {build(src.stem)}")
        except NativeUnavailable as e:
            print(f"cablelab.native: {src.stem}: not built ({e}); the Python path is used", file=sys.stderr)
            rc = 1
    return rc


if __name__ == "__main__":
    sys.exit(main())
