"""Reading what is intact in a damaged or unfinished MCAP file, chunk by chunk.

An MCAP file (https://mcap.dev/spec) is a sequence of records ``opcode (u8), length (u64),
content``; messages live in Chunk records, each followed by MessageIndex records listing the
``(log_time, offset)`` of its messages per channel, and a complete file ends with a summary
(Schema, Channel, ChunkIndex, Statistics records) and a footer. :func:`salvage_mcap` walks the
records from the start and decodes every chunk on its own: a chunk is *damaged* if its header,
compression, CRC (when the writer stored one), record structure, channel ids, log times (outside
the chunk's own time range) or message count (against the MessageIndex records after it) do not
hold; it is skipped and counted, the reader moves on to the next record, and if the record
lengths themselves are damaged it finds the next chunk again from the summary's chunk index (or
by scanning for the next chunk that decodes). A record running past the end of the file is the
unfinished tail of a killed writer (``truncated``), not damage.

Without chunk CRCs (rosbags and cablelab write none; ``ros2 bag record`` writes them) damage
confined to message payload bytes cannot be detected; everything that touches record headers is.
"""
from __future__ import annotations

import struct
import zlib
from dataclasses import dataclass, field

from ..mcap_index import MAGIC

_U16, _U32, _U64 = struct.Struct("<H"), struct.Struct("<I"), struct.Struct("<Q")
_OP_HEADER, _OP_FOOTER, _OP_SCHEMA, _OP_CHANNEL, _OP_MESSAGE = 0x01, 0x02, 0x03, 0x04, 0x05
_OP_CHUNK, _OP_MESSAGE_INDEX, _OP_CHUNK_INDEX, _OP_STATISTICS, _OP_DATA_END = 0x06, 0x07, 0x08, 0x0B, 0x0F
_KNOWN = set(range(0x01, 0x10))


class _Damaged(Exception):
    """A record that does not decode (caught per chunk)."""


@dataclass
class Salvage:
    """What :func:`salvage_mcap` read: per topic log times (ns) and serialised messages, and
    counts of chunks (``chunks`` in all, ``damaged`` skipped), of ``lost`` messages (None if the
    file does not say how many) and whether the file ended part-way (``truncated``)."""

    topics: dict[str, str] = field(default_factory=dict)
    times: dict[str, list] = field(default_factory=dict)
    raws: dict[str, list] = field(default_factory=dict)
    chunks: int = 0
    damaged: int = 0
    lost: int | None = 0
    truncated: bool = False

    @property
    def messages(self) -> int:
        return sum(len(v) for v in self.times.values())

    def describe(self) -> str:
        """e.g. ``skipped 1 damaged chunk of 57, 1000 messages lost``."""
        lost = "an unknown number of" if self.lost is None else str(self.lost)
        s = "" if self.damaged == 1 else "s"
        return f"skipped {self.damaged} damaged chunk{s} of {self.chunks}, {lost} messages lost"


def _string(buf, pos: int, end: int) -> tuple[str, int]:
    if pos + 4 > end:
        raise _Damaged("string length past the record")
    (n,) = _U32.unpack_from(buf, pos)
    if pos + 4 + n > end:
        raise _Damaged("string past the record")
    try:
        return bytes(buf[pos + 4:pos + 4 + n]).decode("utf-8"), pos + 4 + n
    except UnicodeDecodeError:
        raise _Damaged("string not UTF-8") from None


def _schema(buf, a: int, b: int) -> tuple[int, str]:
    if a + 2 > b:
        raise _Damaged("short schema")
    (sid,) = _U16.unpack_from(buf, a)
    name, _ = _string(buf, a + 2, b)
    return sid, name


def _channel(buf, a: int, b: int) -> tuple[int, int, str]:
    if a + 4 > b:
        raise _Damaged("short channel")
    cid, sid = struct.unpack_from("<HH", buf, a)
    topic, _ = _string(buf, a + 4, b)
    if not topic.startswith("/"):
        raise _Damaged("channel topic")
    return cid, sid, topic


def _records(buf, start: int, end: int):
    pos = start
    while pos < end:
        if pos + 9 > end:
            raise _Damaged("record header past the end")
        op = buf[pos]
        (n,) = _U64.unpack_from(buf, pos + 1)
        if op not in _KNOWN or pos + 9 + n > end:
            raise _Damaged("bad record")
        yield op, pos + 9, pos + 9 + n
        pos += 9 + n


def _decode_chunk(data, a: int, b: int, schemas: dict, channels: dict) -> list[tuple[int, int, bytes]]:
    """(channel id, log time, payload) of every message of the chunk in data[a:b]; new schemas
    and channels of the chunk are added to ``schemas``/``channels``. Raises _Damaged."""
    if a + 28 > b:
        raise _Damaged("short chunk")
    t0, t1, usize, crc = struct.unpack_from("<QQQI", data, a)
    comp, p = _string(data, a + 28, b)
    if p + 8 > b:
        raise _Damaged("short chunk")
    (rlen,) = _U64.unpack_from(data, p)
    raw = data[p + 8:p + 8 + rlen]
    if p + 8 + rlen != b or t0 > t1:
        raise _Damaged("chunk lengths")
    try:
        if comp == "":
            dec = bytes(raw)
        elif comp == "zstd":
            import zstandard

            dec = zstandard.ZstdDecompressor().decompress(bytes(raw), max_output_size=usize)
        elif comp == "lz4":
            import lz4.frame

            dec = lz4.frame.decompress(bytes(raw))
        else:
            raise _Damaged(f"compression {comp!r}")
    except _Damaged:
        raise
    except Exception as exc:  # noqa: BLE001 - any decompressor error: the chunk is damaged
        raise _Damaged(f"decompression ({type(exc).__name__})") from None
    if len(dec) != usize or (crc and zlib.crc32(dec) != crc):
        raise _Damaged("chunk size or CRC")
    new_schemas, new_channels, msgs = {}, {}, []
    for op, ra, rb in _records(dec, 0, len(dec)):
        if op == _OP_SCHEMA:
            sid, name = _schema(dec, ra, rb)
            new_schemas[sid] = name
        elif op == _OP_CHANNEL:
            cid, sid, topic = _channel(dec, ra, rb)
            new_channels[cid] = (topic, sid)
        elif op == _OP_MESSAGE:
            if ra + 22 > rb:
                raise _Damaged("short message")
            cid, _seq, log_time = struct.unpack_from("<HIQ", dec, ra)
            if cid not in channels and cid not in new_channels:
                raise _Damaged("unknown channel")
            if not t0 <= log_time <= t1:
                raise _Damaged("log time outside the chunk")
            msgs.append((cid, log_time, dec[ra + 22:rb]))
        else:
            raise _Damaged(f"record {op:#x} inside a chunk")
    schemas.update(new_schemas)
    channels.update(new_channels)
    return msgs


def _summary(data: bytes) -> tuple[dict, dict, list[int], int | None]:
    """(schemas, channels, chunk start offsets, message count) from the summary section, or
    empty ones if the file has no readable summary."""
    schemas, channels, starts, count = {}, {}, [], None
    if len(data) < 8 + 8 + 29 or data[-8:] != MAGIC:
        return schemas, channels, starts, count
    footer = len(data) - 8 - 29
    if data[footer] != _OP_FOOTER:
        return schemas, channels, starts, count
    (summary_start,) = _U64.unpack_from(data, footer + 9)
    if not 8 <= summary_start <= footer:
        return schemas, channels, starts, count
    try:
        for op, a, b in _records(data, summary_start, footer):
            if op == _OP_SCHEMA:
                sid, name = _schema(data, a, b)
                schemas[sid] = name
            elif op == _OP_CHANNEL:
                cid, sid, topic = _channel(data, a, b)
                channels[cid] = (topic, sid)
            elif op == _OP_CHUNK_INDEX and a + 32 <= b:
                starts.append(_U64.unpack_from(data, a + 16)[0])
            elif op == _OP_STATISTICS and a + 8 <= b:
                (count,) = _U64.unpack_from(data, a)
    except (_Damaged, struct.error):
        pass
    return schemas, channels, sorted(s for s in starts if 8 <= s < len(data)), count


def salvage_mcap(path, expected_messages: int | None = None) -> Salvage:
    """Read every intact chunk of the MCAP file ``path`` (see the module docstring).

    Args:
        expected_messages: the file's message count from elsewhere (metadata.yaml), used for
            ``lost`` when the file has no statistics and a damaged chunk no message index.
    """
    with open(path, "rb") as fh:
        data = fh.read()
    out = Salvage()
    schemas, channels, chunk_starts, stat_count = _summary(data)
    complete = data[-8:] == MAGIC and len(data) > 16
    msgs: list[tuple[int, int, bytes]] = []
    good_chunks = 0
    seen_chunks: set[int] = set()
    lost_by_index = 0
    lost_unknown = False
    pending = None            # (offset, messages or None if damaged) of the last chunk
    pending_index = 0         # messages its MessageIndex records list

    def settle(index_complete: bool = True):
        nonlocal pending, pending_index, good_chunks, lost_by_index, lost_unknown
        if pending is None:
            return
        off, got = pending
        if got is not None and index_complete and pending_index and len(got) != pending_index:
            got = None        # the index after the chunk disagrees with what decoded
        if got is None:
            out.damaged += 1
            if pending_index:
                lost_by_index += pending_index
            else:
                lost_unknown = True
        else:
            good_chunks += 1
            msgs.extend(got)
        pending, pending_index = None, 0

    def resync(pos: int) -> int:
        """Offset of the next chunk after ``pos`` (summary index, else a scan), or len(data)."""
        later = [s for s in chunk_starts if s > pos]
        if later:
            return later[0]
        p = pos
        while True:
            p = data.find(bytes([_OP_CHUNK]), p + 1)
            if p < 0 or p + 9 > len(data):
                return len(data)
            (n,) = _U64.unpack_from(data, p + 1)
            if p + 9 + n <= len(data):
                try:
                    _decode_chunk(data, p + 9, p + 9 + n, dict(schemas), dict(channels))
                    return p
                except (_Damaged, struct.error):
                    pass

    pos = 8 if data[:8] == MAGIC else len(data)
    while pos + 9 <= len(data):
        op = data[pos]
        (n,) = _U64.unpack_from(data, pos + 1)
        end = pos + 9 + n
        if op not in _KNOWN or end > len(data):
            if end > len(data) and not complete and op in _KNOWN:
                out.truncated = True        # the writer was killed inside this record
                break
            settle()                        # a damaged record header: on to the next chunk
            nxt = resync(pos)
            skipped = sum(1 for s in chunk_starts if pos <= s < nxt) if chunk_starts else 1
            out.damaged += skipped
            lost_unknown = lost_unknown or skipped > 0
            pos = nxt
            continue
        if op != _OP_MESSAGE_INDEX:
            settle()
        try:
            if op == _OP_CHUNK:
                seen_chunks.add(pos)
                try:
                    pending = (pos, _decode_chunk(data, pos + 9, end, schemas, channels))
                except (_Damaged, struct.error):
                    pending = (pos, None)
            elif op == _OP_MESSAGE_INDEX and pending is not None:
                if pos + 15 <= end:
                    (rlen,) = _U32.unpack_from(data, pos + 11)
                    pending_index += rlen // 16
            elif op == _OP_SCHEMA:
                sid, name = _schema(data, pos + 9, end)
                schemas[sid] = name
            elif op == _OP_CHANNEL:
                cid, sid, topic = _channel(data, pos + 9, end)
                channels[cid] = (topic, sid)
            elif op == _OP_MESSAGE:
                cid, _seq, log_time = struct.unpack_from("<HIQ", data, pos + 9)
                if cid in channels and pos + 9 + 22 <= end:
                    msgs.append((cid, log_time, data[pos + 9 + 22:end]))
            elif op in (_OP_DATA_END, _OP_FOOTER):
                break
        except (_Damaged, struct.error):
            pass   # a damaged schema/channel record outside chunks: the summary may have it
        pos = end
    else:
        if pos < len(data) and not complete:
            out.truncated = True
    settle(index_complete=not out.truncated)   # a cut inside the index after the last chunk
    out.chunks = max(len(chunk_starts), good_chunks + out.damaged)
    total = stat_count if stat_count is not None else expected_messages
    for cid, (topic, sid) in channels.items():
        out.topics.setdefault(topic, schemas.get(sid, ""))
        out.times.setdefault(topic, [])
        out.raws.setdefault(topic, [])
    for cid, log_time, payload in msgs:
        topic = channels[cid][0]
        out.times[topic].append(log_time)
        out.raws[topic].append(bytes(payload))
    if out.damaged == 0:
        out.lost = 0
    elif total is not None:
        out.lost = max(int(total) - out.messages, 0)
    else:
        out.lost = None if lost_unknown else lost_by_index
    return out
