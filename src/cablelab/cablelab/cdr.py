"""Vectorised CDR (de)serialisation of ROS 2 messages over numpy byte matrices.

rosbags' generated (de)serialisers handle one message per Python call (~100 k JointState/s).
Recorded topics almost always repeat one byte *layout* (same joint names, same array lengths,
same frame id): only the numbers change. This module exploits that:

* :func:`walk` parses one serialised message and returns its :class:`Layout`: the byte span of
  every numeric leaf (``"header.stamp.sec"``, ``"position"``, ``"points[0].positions"``, ...),
  the text of every string and the length of every sequence. It follows the XCDR1 rules used by
  rmw_fastrtps and rosbags (alignment relative to the end of the 4-byte encapsulation header;
  primitive sequences aligned only when non-empty).
* :func:`decode` groups N messages by identical *structural* bytes (everything that is not a
  numeric leaf: lengths, strings, padding). Within a group the layout is provably identical (the
  walk reads only structural bytes to find positions), so every numeric field of the whole group
  is one strided slice of an (n, L) uint8 matrix viewed as ``<f8``/``<i4``. Messages that fit no
  common layout fall back to a per-message walk (still correct, slower).
* :func:`encode` serialises one template message with rosbags, then broadcasts it to (N, L) and
  overwrites the numeric spans column-block-wise.

The reference implementation used as oracle in the tests is rosbags' own serialiser.
"""
from __future__ import annotations

import struct
from dataclasses import dataclass, field
from functools import lru_cache

import numpy as np

from .errors import CablelabError

_SIZES = {
    "bool": 1, "byte": 1, "char": 1, "int8": 1, "uint8": 1, "octet": 1,
    "int16": 2, "uint16": 2, "int32": 4, "uint32": 4, "float32": 4,
    "int64": 8, "uint64": 8, "float64": 8,
}
_KINDS = {
    "bool": "u1", "byte": "u1", "char": "u1", "int8": "i1", "uint8": "u1", "octet": "u1",
    "int16": "i2", "uint16": "u2", "int32": "i4", "uint32": "u4", "float32": "f4",
    "int64": "i8", "uint64": "u8", "float64": "f8",
}
_BASE, _NAME, _ARRAY, _SEQUENCE = 1, 2, 3, 4  # rosbags Nodetype values


@lru_cache(maxsize=1)
def typestore():
    """The ROS 2 Jazzy typestore of rosbags (message definitions and reference serialiser)."""
    from rosbags.typesys import Stores, get_typestore

    return get_typestore(Stores.ROS2_JAZZY)


@dataclass
class Layout:
    """Byte layout of one serialised message.

    Attributes:
        spans: path -> (byte offset in the message incl. the 4-byte header, count, numpy dtype str)
        strings: path -> text of every string field (``"name[2]"``, ``"header.frame_id"``)
        seqlen: path -> number of elements of every sequence
        size: total length in bytes
        end: where the message's last field ends (bytes after it are padding, possibly
            uninitialised: rmw_fastrtps sizes a message with 8 bytes of alignment per empty
            float64 sequence that the serialiser does not write)
        padding: (offset, length) of every alignment gap between fields
    """

    spans: dict[str, tuple[int, int, str]] = field(default_factory=dict)
    strings: dict[str, str] = field(default_factory=dict)
    seqlen: dict[str, int] = field(default_factory=dict)
    size: int = 0
    end: int = 0
    padding: list = field(default_factory=list)

    def numeric_mask(self) -> np.ndarray:
        """Boolean mask (size,) that is True on bytes that do not determine the layout: numeric
        leaf values, alignment padding (rclpy's serialiser leaves it uninitialised) and the
        trailing padding."""
        mask = np.zeros(self.size, dtype=bool)
        mask[self.end:] = True
        for off, n in self.padding:
            mask[off:off + n] = True
        for off, count, dt in self.spans.values():
            mask[off:off + count * int(dt[-1])] = True
        return mask


class _Walker:
    def __init__(self, buf: bytes):
        self.buf = buf
        if len(buf) < 4:
            raise ValueError("message shorter than the 4-byte CDR header")
        self.little = buf[1] in (1, 3)
        self.end = "<" if self.little else ">"
        self.u32 = struct.Struct(self.end + "I")
        self.pos = 4
        self.out = Layout()

    def align(self, n: int) -> None:
        rel = self.pos - 4
        pos = 4 + ((rel + n - 1) & -n)
        if pos > self.pos:          # alignment padding: serialisers may leave it uninitialised
            self.out.padding.append((self.pos, pos - self.pos))
        self.pos = pos

    def count(self) -> int:
        self.align(4)
        if self.pos + 4 > len(self.buf):
            raise ValueError("message truncated")
        (n,) = self.u32.unpack_from(self.buf, self.pos)
        self.pos += 4
        return n

    def string(self, path: str) -> None:
        n = self.count()
        if self.pos + n > len(self.buf):
            raise ValueError(f"string {path} runs past the end of the message")
        self.out.strings[path] = self.buf[self.pos:self.pos + max(n - 1, 0)].decode("utf-8", "replace")
        self.pos += n

    def prim(self, path: str, typ: str, count: int, always_align: bool) -> None:
        size = _SIZES[typ]
        if count or always_align:
            self.align(size)
        if count:
            self.out.spans[path] = (self.pos, count, self.end + _KINDS[typ])
        self.pos += size * count
        if self.pos > len(self.buf):
            raise ValueError(f"field {path} runs past the end of the message")

    def node(self, desc, path: str) -> None:
        kind, arg = desc
        if kind == _BASE:
            typ = arg[0]
            if typ == "string" or typ == "wstring":
                self.string(path)
            else:
                self.prim(path, typ, 1, True)
        elif kind == _NAME:
            self.message(arg, path + ".")
        elif kind in (_ARRAY, _SEQUENCE):
            sub, length = arg
            n = self.count() if kind == _SEQUENCE else length
            if kind == _SEQUENCE:
                self.out.seqlen[path] = n
            if sub[0] == _BASE and sub[1][0] not in ("string", "wstring"):
                self.prim(path, sub[1][0], n, kind == _ARRAY and n > 0)
            else:
                for i in range(n):
                    self.node(sub, f"{path}[{i}]")
        else:  # pragma: no cover - rosbags has no other node types
            raise ValueError(f"unsupported field kind {kind}")

    def message(self, msgtype: str, prefix: str = "") -> None:
        for name, desc in typestore().fielddefs[msgtype][1]:
            self.node(desc, prefix + name)


def walk(msgtype: str, buf: bytes) -> Layout:
    """Parse one serialised message and return its :class:`Layout`.

    Raises:
        ValueError: the bytes are not a valid CDR message of ``msgtype``.
    """
    w = _Walker(buf)
    w.message(msgtype)
    # trailing padding: rmw_fastrtps reserves 8 bytes per empty sequence (see Layout.end)
    if not (w.pos <= len(buf) <= w.pos + 8 * (1 + len(w.out.seqlen))):
        raise ValueError(f"message has {len(buf)} bytes, layout of {msgtype} needs {w.pos}")
    w.out.size = len(buf)
    w.out.end = w.pos
    return w.out


@dataclass
class Group:
    """Messages sharing one layout: ``rows`` indexes into the decoded list, ``mat`` (n, L) bytes."""

    rows: np.ndarray
    layout: Layout
    mat: np.ndarray

    def get(self, path: str, dtype=np.float64) -> np.ndarray | None:
        """(n, count) values of a numeric field, or None if the field is empty in this layout."""
        span = self.layout.spans.get(path)
        if span is None:
            return None
        off, count, dt = span
        nbytes = count * int(dt[-1])
        block = np.ascontiguousarray(self.mat[:, off:off + nbytes])
        return block.view(dt).reshape(len(self.rows), count).astype(dtype, copy=False)

    def stamp(self, path: str = "header.stamp") -> np.ndarray:
        """(n,) time in seconds of a builtin_interfaces/Time field."""
        sec = self.get(path + ".sec", np.int64)
        nsec = self.get(path + ".nanosec", np.int64)
        return (sec[:, 0] * 1_000_000_000 + nsec[:, 0]) * 1e-9


def decode(msgtype: str, raws: list[bytes], *, topic: str = "", max_layouts: int = 64) -> list[Group]:
    """Split serialised messages into groups of identical layout (see module docstring).

    Args:
        msgtype: e.g. ``"sensor_msgs/msg/JointState"``
        raws: serialised messages (CDR with 4-byte encapsulation header)
        topic: only for error messages
        max_layouts: after this many distinct layouts the rest is decoded one message at a time

    Raises:
        CablelabError: a message is not a valid ``msgtype`` (names the topic and message index).
    """
    lengths = np.fromiter((len(r) for r in raws), dtype=np.int64, count=len(raws))
    offsets = np.concatenate([[0], np.cumsum(lengths)[:-1]]).astype(np.int64) if len(raws) else lengths
    return decode_buffer(msgtype, memoryview(b"".join(raws)), offsets, lengths, topic=topic,
                         max_layouts=max_layouts)


def decode_buffer(msgtype: str, buf, offsets: np.ndarray, lengths: np.ndarray, *, topic: str = "",
                  max_layouts: int = 64) -> list[Group]:
    """:func:`decode` of messages stored at ``buf[offsets[i]:offsets[i] + lengths[i]]``."""
    if len(offsets) == 0:
        return []
    buf = memoryview(buf)
    groups: list[Group] = []
    for L in np.unique(lengths):
        L = int(L)
        idx = np.flatnonzero(lengths == L)
        joined = b"".join([buf[o:o + L] for o in offsets[idx].tolist()])
        mat = np.frombuffer(joined, dtype=np.uint8).reshape(len(idx), L)
        remaining = np.arange(len(idx))
        while remaining.size:
            first = remaining[0]
            try:
                layout = walk(msgtype, bytes(mat[first]))
            except (ValueError, KeyError, UnicodeError, struct.error) as exc:
                raise CablelabError(f"{topic or msgtype}: message {int(idx[first])} is not a valid "
                                    f"{msgtype} ({exc})") from None
            if len(groups) >= max_layouts:
                match = np.zeros(remaining.size, dtype=bool)
                match[0] = True
            else:
                struct_cols = np.flatnonzero(~layout.numeric_mask())
                sub = (mat if remaining.size == len(mat) else mat[remaining])[:, struct_cols]
                match = (sub == mat[first, struct_cols]).all(axis=1)
            rows = remaining[match]
            groups.append(Group(rows=idx[rows], layout=layout, mat=mat[rows]))
            remaining = remaining[~match]
    return groups


def encode(msgtype: str, template, fills: dict[str, np.ndarray], n: int) -> tuple[np.ndarray, int]:
    """Serialise n messages that share the layout of ``template`` (a rosbags message object).

    Args:
        fills: path -> values, shape (n,) or (n, count), written into that numeric field
            (e.g. ``{"header.stamp.sec": sec, "position": pos}``); other fields keep the template's.

    Returns:
        (flat uint8 array of n * L bytes, L)
    """
    buf = typestore().serialize_cdr(template, msgtype)
    layout = walk(msgtype, bytes(buf))
    L = layout.size
    mat = np.empty((n, L), dtype=np.uint8)
    mat[:] = np.frombuffer(buf, dtype=np.uint8)
    for path, values in fills.items():
        if values is None:
            continue
        span = layout.spans.get(path)
        if span is None:
            raise KeyError(f"{msgtype} template has no numeric field {path!r}")
        off, count, dt = span
        v = np.ascontiguousarray(np.asarray(values).astype(dt, copy=False).reshape(n, count))
        mat[:, off:off + count * int(dt[-1])] = v.view(np.uint8).reshape(n, -1)
    return mat.reshape(-1), L
