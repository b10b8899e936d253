"""Find the bags of a fleet tree, their machine and start time, and their content hash.

ROOT is a local path or any URL fsspec understands (``s3://``, ``gcs://``, ``file://``, ...).
A bag is a directory holding a ``.mcap`` file or a rosbag2 ``metadata.yaml`` (CONTRACT section 5),
or a bare ``.mcap`` file whose directory is not a bag. Machine id and time come from the bag
(description ``name``, first stamp) in the per-bag task unless a ``--group-by`` pattern names them
from the path.
"""
from __future__ import annotations

import dataclasses
import datetime as _dt
import hashlib
import posixpath
import re

from ..errors import CablelabError


@dataclasses.dataclass(frozen=True)
class BagRef:
    """One bag found under ROOT: ``url`` (what the task opens), ``rel`` (path relative to ROOT,
    '/'-separated) and the machine / start time given by the ``--group-by`` pattern (or None)."""

    url: str
    rel: str
    machine: str | None = None
    start_time: _dt.datetime | None = None


def filesystem(root: str):
    """``(fs, path)`` of a local path or fsspec URL."""
    import fsspec

    try:
        fs, path = fsspec.core.url_to_fs(str(root))
    except (ImportError, ValueError) as exc:
        raise CablelabError(f"{root}: cannot open this location ({exc})") from None
    return fs, path


def is_local(fs) -> bool:
    proto = fs.protocol if isinstance(fs.protocol, str) else fs.protocol[0]
    return proto in ("file", "local")


def _url(fs, path: str) -> str:
    return path if is_local(fs) else fs.unstrip_protocol(path)


def find_bags(root: str, group_by: str | None = None) -> list[BagRef]:
    """Every bag under ``root`` (sorted by relative path).

    Raises:
        CablelabError: ROOT does not exist, or a ``group_by`` pattern that does not match a bag
            (the message names the bag and the pattern).
    """
    fs, base = filesystem(root)
    if not fs.exists(base):
        raise CablelabError(f"{root}: no such directory")
    if fs.isfile(base):
        files = [base]
        base = posixpath.dirname(base)
    else:
        files = fs.find(base)
    dirs, bare = set(), []
    for f in files:
        name = posixpath.basename(f)
        if name == "metadata.yaml" or name.endswith(".mcap"):
            dirs.add(posixpath.dirname(f))
    for f in files:
        if f.endswith(".mcap") and posixpath.dirname(f) not in dirs:
            bare.append(f)
    pattern = compile_group_by(group_by) if group_by else None
    out = []
    for p in sorted(dirs | set(bare)):
        rel = posixpath.relpath(p, base) if p != base else posixpath.basename(p)
        machine, start = (None, None)
        if pattern is not None:
            machine, start = match_group_by(pattern, rel, group_by)
        out.append(BagRef(_url(fs, p), rel, machine, start))
    return out


def compile_group_by(pattern: str) -> re.Pattern:
    """A ``--group-by`` path pattern as a regex over the bag's path relative to ROOT.

    Placeholders: ``{machine}`` (one path component or part of one), ``{date}`` (``YYYY-MM-DD``,
    ``YYYYMMDD`` or an ISO 8601 date-time), ``*`` (any text within a component), ``**`` (any
    text). Example: ``{machine}/{date}/*``.
    """
    out, i = [], 0
    tokens = re.split(r"(\{machine\}|\{date\}|\*\*|\*)", pattern)
    for tok in tokens:
        if tok == "{machine}":
            out.append(r"(?P<machine>[^/]+?)")
        elif tok == "{date}":
            out.append(r"(?P<date>[0-9][0-9T:\-+.Z_]*[0-9Z])")
        elif tok == "**":
            out.append(r".*")
        elif tok == "*":
            out.append(r"[^/]*")
        elif tok:
            if "{" in tok or "}" in tok:
                raise CablelabError(f"--group-by {pattern}: unknown placeholder in {tok!r} "
                                    "(use {machine}, {date}, *, **)")
            out.append(re.escape(tok))
        i += 1
    return re.compile("".join(out))


def parse_date(text: str) -> _dt.datetime:
    """UTC datetime of ``YYYY-MM-DD``, ``YYYYMMDD`` or ISO 8601 text (naive = UTC)."""
    s = text.replace("_", "T")
    if re.fullmatch(r"\d{8}", s):
        s = f"{s[:4]}-{s[4:6]}-{s[6:]}"
    d = _dt.datetime.fromisoformat(s.replace("Z", "+00:00"))
    return d.replace(tzinfo=_dt.timezone.utc) if d.tzinfo is None else d.astimezone(_dt.timezone.utc)


def match_group_by(regex: re.Pattern, rel: str, pattern: str):
    """``(machine, start_time)`` of a bag path by a compiled ``--group-by`` pattern."""
    m = regex.fullmatch(rel) or regex.match(rel)
    if m is None:
        raise CablelabError(f"{rel}: does not match --group-by {pattern}")
    g = m.groupdict()
    start = None
    if g.get("date"):
        try:
            start = parse_date(g["date"])
        except ValueError:
            raise CablelabError(f"{rel}: {g['date']!r} (the {{date}} of --group-by {pattern}) is not "
                                "a date") from None
    return g.get("machine"), start


def content_hash(url: str) -> str:
    """sha256 (hex, 16 chars) of a bag's files: names and bytes of every file directly in the bag
    directory (or of the one .mcap file), read where they lie. Unreadable: hash of the error."""
    fs, path = filesystem(url)
    h = hashlib.sha256()
    try:
        files = [path] if fs.isfile(path) else sorted(f for f in fs.ls(path, detail=False) if fs.isfile(f))
        for f in files:
            h.update(posixpath.basename(f).encode() + b"\0")
            with fs.open(f, "rb") as fh:
                for chunk in iter(lambda: fh.read(1 << 20), b""):
                    h.update(chunk)
    except OSError as exc:
        h.update(f"unreadable {exc}".encode())
    return h.hexdigest()[:16]
