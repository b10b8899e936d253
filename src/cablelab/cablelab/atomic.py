"""Outputs that appear whole or not at all, never over an input, never replaced unasked.

Every verb that writes a file or directory (``estimate --out``, ``report -o``, ``import -o``)
writes through :func:`atomic_output`: the target is checked first (exists without
``--overwrite``, is or contains or lies inside an input, parent missing or not writable: one-line
:class:`~cablelab.errors.CablelabError`), the content is written under a hidden temporary name
in the same directory and moved into place with one ``rename`` when complete. A full disk, a
read-only file system or a kill part-way leaves no partial output (the temporary is removed on
errors; a SIGKILL leaves only a hidden ``.NAME.partial-PID`` entry) and the old output intact.
"""
from __future__ import annotations

import contextlib
import errno
import os
import shutil
from pathlib import Path

from .errors import CablelabError


def _same_or_nested(a: Path, b: Path) -> bool:
    a, b = a.resolve(), b.resolve()
    return a == b or a in b.parents or b in a.parents


def check_target(path, *, overwrite: bool = False, inputs=(), option: str = "--out") -> Path:
    """Validate an output path before any work is done.

    Args:
        path: file or directory to create. overwrite: an existing target may be replaced.
        inputs: paths read by the verb; the output may not be, contain or lie inside one.
        option: the option naming the output (for messages).
    Raises:
        CablelabError: one line naming the path and what to do.
    """
    target = Path(path)
    if not str(path).strip():
        raise CablelabError(f"{option}: empty output path")
    for inp in inputs:
        if inp and Path(inp).exists() and _same_or_nested(target, Path(inp)):
            raise CablelabError(f"{target}: {option} would write into the input {inp}; choose another path")
    if target.exists() or target.is_symlink():
        if not overwrite:
            raise CablelabError(f"{target}: exists already (use --overwrite to replace it)")
    parent = target.parent if str(target.parent) else Path(".")
    if not parent.is_dir():
        raise CablelabError(f"{target}: parent directory {parent} does not exist")
    if not os.access(parent, os.W_OK | os.X_OK):
        raise CablelabError(f"{target}: directory {parent} is not writable")
    return target


def os_error_message(path, exc: OSError) -> str:
    """One line for an OSError while writing ``path`` (disk full, read-only, permission)."""
    why = {errno.ENOSPC: "no space left on device", errno.EDQUOT: "disk quota exceeded",
           errno.EROFS: "read-only file system", errno.EACCES: "permission denied",
           errno.EPERM: "operation not permitted"}.get(exc.errno, exc.strerror or type(exc).__name__)
    return f"{path}: cannot write ({why}); nothing was written"


def _os_error_in_chain(exc: BaseException) -> OSError | None:
    seen = 0
    while exc is not None and seen < 10:
        if isinstance(exc, OSError) and exc.errno is not None:
            return exc
        exc = exc.__cause__ or exc.__context__
        seen += 1
    return None


def _remove(p: Path) -> None:
    if p.is_dir() and not p.is_symlink():
        shutil.rmtree(p, ignore_errors=True)
    elif p.exists() or p.is_symlink():
        with contextlib.suppress(OSError):
            p.unlink()


@contextlib.contextmanager
def atomic_output(path, *, overwrite: bool = False, inputs=(), option: str = "--out"):
    """Context manager yielding a temporary path to write ``path``'s content to (file or
    directory, not yet existing, same directory so the final move is one rename).

    On normal exit the temporary replaces ``path``; on any exception it is removed and ``path``
    is untouched. OSErrors (disk full, read-only, permission) become a one-line CablelabError.
    """
    target = check_target(path, overwrite=overwrite, inputs=inputs, option=option)
    parent = target.parent if str(target.parent) else Path(".")
    tmp_dir = parent / f".{target.name}.partial-{os.getpid()}"
    _remove(tmp_dir)
    try:
        tmp_dir.mkdir()
    except OSError as exc:
        raise CablelabError(os_error_message(target, exc)) from None
    tmp = tmp_dir / target.name  # same basename: a bag directory keeps its .mcap file name
    try:
        try:
            yield tmp
            if not (tmp.exists() or tmp.is_symlink()):
                raise CablelabError(f"{target}: nothing was written")
            old = None
            if target.exists() or target.is_symlink():
                old = parent / f".{target.name}.old-{os.getpid()}"
                _remove(old)
                os.rename(target, old)
            try:
                os.rename(tmp, target)
            except OSError:
                if old is not None:
                    os.rename(old, target)
                raise
            if old is not None:
                _remove(old)
        except CablelabError:
            raise
        except Exception as exc:  # noqa: BLE001 - writers wrap OSError in their own types
            os_exc = _os_error_in_chain(exc)
            if os_exc is None:
                raise
            raise CablelabError(os_error_message(target, os_exc)) from None
    finally:
        _remove(tmp_dir)
