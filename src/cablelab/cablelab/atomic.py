"""Outputs that appear whole or not at all, never over an input, never replaced unasked, never
written by two processes at once.

Every verb that writes a directory (``estimate --out``, ``report -o``, ``import -o``, ``repair
-o``) writes through :func:`atomic_output`: the target is checked first (exists without
``--overwrite``, is or contains or lies inside an input, parent missing or not writable: one-line
:class:`~cablelab.errors.CablelabError`), the content is written under a hidden temporary name
in the same directory and moved into place with one ``rename`` when complete. A full disk, a
read-only file system or a kill part-way leaves no partial output (the temporary is removed on
errors; a SIGKILL leaves only a hidden ``.NAME.partial-PID`` entry) and the old output intact.

Only what cablelab wrote is ever replaced: every output directory carries the marker file
:data:`MARKER` (``.cablelab-output``: the verb, then every entry it wrote), and ``--overwrite``
replaces a target only if it is a real directory holding that marker and nothing the marker does
not list (or an empty directory). A plain file, a symlink, a directory of the user's own or an
output the user added files to is refused with one line naming it; nothing is deleted.

An input bag given as its ``.mcap`` file counts as its whole bag directory (the directory holding
the file and its ``metadata.yaml``): an output may not be written inside it.

Two processes writing one output are refused: :func:`lock_target` takes an exclusive
``fcntl.flock`` on a hidden lock file beside the target (``.NAME.lock``, holding the owner's pid),
held from the first check to the final rename (or for the whole run of ``batch`` and ``record``);
a second writer gets "TARGET: is being written by another cablelab process (pid N)".
"""
from __future__ import annotations

import atexit
import contextlib
import errno
import fcntl
import os
import shutil
from pathlib import Path

from .errors import CablelabError


#: the file every output directory of a cablelab verb carries (its text: the verb)
MARKER = ".cablelab-output"


def _same_or_nested(a: Path, b: Path) -> bool:
    a, b = a.resolve(), b.resolve()
    return a == b or a in b.parents or b in a.parents


def input_paths(inp) -> list[Path]:
    """The paths an input stands for: itself, and for a ``.mcap`` file of a bag directory (one
    with ``metadata.yaml``, or holding nothing but .mcap/.yaml files) that directory too."""
    p = Path(inp)
    out = [p]
    if p.suffix == ".mcap" and p.is_file():
        d = p.resolve().parent
        try:
            others = [e for e in d.iterdir() if e.name != MARKER]
        except OSError:
            others = []
        if (d / "metadata.yaml").exists() or all(e.suffix in (".mcap", ".yaml") for e in others):
            out.append(d)
    return out


def _entries(d: Path) -> list[str]:
    """Relative paths of every file, directory and link under ``d`` (but the marker)."""
    return sorted(p.relative_to(d).as_posix() for p in d.rglob("*") if p.name != MARKER or p.parent != d)


def write_marker(directory, verb: str) -> None:
    """Mark ``directory`` as an output cablelab wrote: the marker names the verb, then lists
    every entry the directory holds now (what a later ``--overwrite`` may delete)."""
    d = Path(directory)
    (d / MARKER).write_text("".join(f"{line}\n" for line in [verb] + _entries(d)), encoding="utf-8")


def marker_of(path) -> str | None:
    """The verb named by the marker of ``path`` (a real directory), or None if it has none."""
    lines = _marker_lines(path)
    return (lines[0].strip() or "cablelab") if lines else None


def _marker_lines(path) -> list[str] | None:
    p = Path(path)
    m = p / MARKER
    if p.is_symlink() or not p.is_dir() or m.is_symlink() or not m.is_file():
        return None
    try:
        return m.read_text(encoding="utf-8", errors="replace").split("\n")[:-1] or [""]
    except OSError:
        return None


def foreign_entries(path) -> list[str]:
    """Entries under the marked directory ``path`` that its marker does not list (put there by
    someone else after the verb wrote it); every entry if it has no marker."""
    p = Path(path)
    lines = _marker_lines(p)
    listed = set(lines[1:]) if lines else set()
    try:
        return [e for e in _entries(p) if e not in listed]
    except OSError:
        return ["?"]


def replaceable(path) -> bool:
    """True if ``--overwrite`` may delete ``path``: a real directory cablelab wrote (marker) that
    holds nothing else, or an empty directory."""
    p = Path(path)
    if p.is_symlink() or not p.is_dir():
        return False
    try:
        if not any(p.iterdir()):
            return True
    except OSError:
        return False
    return marker_of(p) is not None and not foreign_entries(p)


def refuse_replacing(target: Path) -> CablelabError:
    """The one-line error for an existing ``target`` that is not a cablelab output."""
    if target.is_symlink():
        what = "is a symbolic link"
    elif target.is_dir() and marker_of(target) is not None:
        extra = foreign_entries(target)
        what = (f"holds {len(extra)} entr{'y' if len(extra) == 1 else 'ies'} cablelab did not write "
                f"({extra[0]}{', ...' if len(extra) > 1 else ''})")
    elif target.is_dir():
        what = f"is a directory cablelab did not write (no {MARKER} file)"
    else:
        what = "is a file, not an output directory cablelab wrote"
    return CablelabError(f"{target}: {what}; not replacing it even with --overwrite "
                         f"(choose another path, or move it away yourself)")


# ---- one writer per output: fcntl.flock on a lock file beside the target
_HELD: dict[str, tuple[int, Path]] = {}


def _lock_path(target: Path) -> Path:
    parent = target.parent if str(target.parent) else Path(".")
    return parent / f".{target.name}.lock"


def _key(target: Path) -> str:
    return str(_lock_path(target).resolve())


def lock_target(path) -> bool:
    """Take the exclusive lock of the output ``path`` for this process (held until
    :func:`release_target` or exit). Returns True if taken now, False if this process held it.

    Raises:
        CablelabError: "PATH: is being written by another cablelab process (pid N)".
    """
    target = Path(path)
    key = _key(target)
    if key in _HELD:
        return False
    lock = _lock_path(target)
    for _ in range(20):
        try:
            fd = os.open(lock, os.O_RDWR | os.O_CREAT | os.O_CLOEXEC, 0o644)
        except OSError as exc:
            raise CablelabError(os_error_message(target, exc)) from None
        try:
            fcntl.flock(fd, fcntl.LOCK_EX | fcntl.LOCK_NB)
        except OSError:
            try:
                pid = os.pread(fd, 32, 0).decode("ascii", "replace").strip() or "unknown"
            finally:
                os.close(fd)
            raise CablelabError(f"{target}: is being written by another cablelab process (pid {pid}); "
                                f"wait for it to finish or choose another path") from None
        try:   # the file may have been unlinked by its previous owner between open and flock
            same = os.fstat(fd).st_ino == os.stat(lock).st_ino
        except FileNotFoundError:
            same = False
        if not same:
            os.close(fd)
            continue
        try:
            os.ftruncate(fd, 0)
            os.pwrite(fd, f"{os.getpid()}\n".encode(), 0)
        except OSError:
            pass   # the lock holds; only the pid in the message is missing
        _HELD[key] = (fd, lock)
        return True
    raise CablelabError(f"{target}: cannot take its lock file {lock}")


def release_target(path) -> None:
    """Give up this process's lock of the output ``path`` (and remove the lock file)."""
    entry = _HELD.pop(_key(Path(path)), None)
    if entry is None:
        return
    fd, lock = entry
    with contextlib.suppress(OSError):
        lock.unlink()
    with contextlib.suppress(OSError):
        os.close(fd)


@atexit.register
def release_all() -> None:
    """Give up every output lock this process holds (the CLI does at the end of each verb)."""
    for fd, lock in list(_HELD.values()):
        with contextlib.suppress(OSError):
            lock.unlink()
        with contextlib.suppress(OSError):
            os.close(fd)
    _HELD.clear()


def _check_inputs(target: Path, inputs, option: str) -> None:
    for inp in inputs:
        if not inp or "://" in str(inp):
            continue
        for p in input_paths(inp):
            if p.exists() and _same_or_nested(target, p):
                raise CablelabError(f"{target}: {option} would write into the input {inp}; "
                                    f"choose another path")


def _check_parent(target: Path) -> Path:
    parent = target.parent if str(target.parent) else Path(".")
    if not parent.is_dir():
        raise CablelabError(f"{target}: parent directory {parent} does not exist")
    if not os.access(parent, os.W_OK | os.X_OK):
        raise CablelabError(f"{target}: directory {parent} is not writable")
    return parent


def check_target(path, *, overwrite: bool = False, inputs=(), option: str = "--out") -> Path:
    """Validate an output path before any work is done, and take its lock.

    Args:
        path: directory to create. overwrite: an existing cablelab output may be replaced.
        inputs: paths read by the verb; the output may not be, contain or lie inside one.
        option: the option naming the output (for messages).
    Raises:
        CablelabError: one line naming the path and what to do.
    """
    target = Path(path)
    if not str(path).strip():
        raise CablelabError(f"{option}: empty output path")
    _check_inputs(target, inputs, option)
    _check_parent(target)
    taken = lock_target(target)
    try:
        if target.exists() or target.is_symlink():
            if not overwrite:
                raise CablelabError(f"{target}: exists already (use --overwrite to replace it)")
            if not replaceable(target):
                raise refuse_replacing(target)
    except CablelabError:
        if taken:
            release_target(target)
        raise
    return target


def claim_output_dir(path, *, inputs=(), option: str = "-o", verb: str = "cablelab") -> bool:
    """A directory a verb adds to over several runs (``batch -o OUT``: resumable): it may not be,
    contain or lie inside an input; an existing non-empty directory must carry the marker of an
    earlier run. Takes the lock (held until :func:`release_target` or exit), creates the
    directory and marks it. Returns True if the lock was taken now (False: already held)."""
    target = Path(path)
    if not str(path).strip():
        raise CablelabError(f"{option}: empty output path")
    _check_inputs(target, inputs, option)
    if not target.exists():
        try:
            target.parent.mkdir(parents=True, exist_ok=True)
        except OSError as exc:
            raise CablelabError(f"{target}: cannot create output directory ({exc.strerror})") from None
    _check_parent(target)
    taken = lock_target(target)
    try:
        if target.exists() or target.is_symlink():
            mark = marker_of(target)
            if mark is not None and mark != verb:
                raise CablelabError(f"{target}: is the output of cablelab {mark}, not of {verb}; "
                                    f"choose a new or empty directory")
            if mark is None and not replaceable(target):   # (adds to it, never deletes)
                if target.is_dir() and not target.is_symlink():
                    raise CablelabError(f"{target}: is a directory cablelab did not write (no {MARKER} "
                                        f"file); not writing into it (choose a new or empty directory)")
                raise refuse_replacing(target)
        try:
            target.mkdir(exist_ok=True)
            if marker_of(target) is None:
                write_marker(target, verb)
        except OSError as exc:
            raise CablelabError(f"{target}: cannot create output directory ({exc.strerror})") from None
    except CablelabError:
        if taken:
            release_target(target)
        raise
    return taken


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
def atomic_output(path, *, overwrite: bool = False, inputs=(), option: str = "--out",
                  verb: str = "cablelab"):
    """Context manager yielding a temporary path to write ``path``'s directory to (not yet
    existing, same directory so the final move is one rename).

    On normal exit the temporary, marked with :data:`MARKER` naming ``verb``, replaces ``path``;
    on any exception it is removed and ``path`` is untouched. OSErrors (disk full, read-only,
    permission) become a one-line CablelabError. The lock of ``path`` is released at the end.
    """
    target = check_target(path, overwrite=overwrite, inputs=inputs, option=option)
    try:
        with _atomic(target, overwrite, verb) as tmp:
            yield tmp
    finally:
        release_target(target)


@contextlib.contextmanager
def _atomic(target: Path, overwrite: bool, verb: str):
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
            if tmp.is_dir() and not tmp.is_symlink():
                write_marker(tmp, verb)
            old = None
            if target.exists() or target.is_symlink():
                if not (overwrite and replaceable(target)):   # appeared while working
                    raise refuse_replacing(target) if overwrite else \
                        CablelabError(f"{target}: exists already (use --overwrite to replace it)")
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
