"""Fast reader of indexed MCAP files: message locations from the index, no per-record parsing.

An MCAP file written completely (``ros2 bag record``, rosbags, cablelab) ends with a summary
section holding Schema, Channel and ChunkIndex records; after each chunk come MessageIndex
records listing ``(log_time, offset)`` of every message of a channel in that chunk. This module
reads those arrays with ``np.frombuffer`` (MCAP spec: https://mcap.dev/spec) and gathers every
message's payload position and length in a few vectorised operations, so reading a bag costs
one file read plus numpy work. Uncompressed, zstd and lz4 chunks are supported.

:func:`read_index` returns None when a file cannot be read this way (no summary, no chunk
index, no message indexes, unknown compression, or message records that disagree with the index
about their log time or lie outside the file: damage); the caller then falls back to a general
reader and, for a damaged file, to :mod:`cablelab.bags.salvage`.
"""
from __future__ import annotations

import struct
from dataclasses import dataclass

import numpy as np

MAGIC = b"\x89MCAP0\r\n"
_OP_FOOTER, _OP_SCHEMA, _OP_CHANNEL, _OP_MESSAGE = 0x02, 0x03, 0x04, 0x05
_OP_CHUNK, _OP_MESSAGE_INDEX, _OP_CHUNK_INDEX, _OP_STATISTICS = 0x06, 0x07, 0x08, 0x0B
_U16, _U32, _U64 = struct.Struct("<H"), struct.Struct("<I"), struct.Struct("<Q")


@dataclass
class TopicIndex:
    """Where the messages of one topic are: payload offsets/lengths into ``Index.buffer``."""

    topic: str
    msgtype: str
    log_time: np.ndarray  # (N,) int64 ns, sorted
    offset: np.ndarray  # (N,) int64 into Index.buffer
    length: np.ndarray  # (N,) int64


@dataclass
class Index:
    buffer: memoryview  # the file bytes (+ decompressed chunks appended)
    topics: dict[str, TopicIndex]


def _string(buf, pos: int) -> tuple[str, int]:
    (n,) = _U32.unpack_from(buf, pos)
    return bytes(buf[pos + 4:pos + 4 + n]).decode("utf-8"), pos + 4 + n


def _records(buf, start: int, end: int):
    """(opcode, content start, content end) of the records in buf[start:end]."""
    pos = start
    while pos + 9 <= end:
        op = buf[pos]
        (n,) = _U64.unpack_from(buf, pos + 1)
        yield op, pos + 9, pos + 9 + n
        pos += 9 + n


def read_index(path) -> Index | None:
    """Index an MCAP file (see module docstring); None if it has no usable summary/index."""
    with open(path, "rb") as fh:
        data = fh.read()
    if len(data) < 8 + 8 + 29 or data[:8] != MAGIC or data[-8:] != MAGIC:
        return None
    footer = len(data) - 8 - 29
    if data[footer] != _OP_FOOTER:
        return None
    (summary_start,) = _U64.unpack_from(data, footer + 9)
    if summary_start == 0:
        return None
    schemas: dict[int, str] = {}
    channels: dict[int, tuple[str, int, str]] = {}
    chunk_indexes = []
    message_count = None
    for op, a, b in _records(data, summary_start, footer):
        if op == _OP_SCHEMA:
            (sid,) = _U16.unpack_from(data, a)
            name, p = _string(data, a + 2)
            schemas[sid] = name
        elif op == _OP_CHANNEL:
            (cid,) = _U16.unpack_from(data, a)
            (sid,) = _U16.unpack_from(data, a + 2)
            topic, p = _string(data, a + 4)
            encoding, p = _string(data, p)
            channels[cid] = (topic, sid, encoding)
        elif op == _OP_CHUNK_INDEX:
            chunk_indexes.append((a, b))
        elif op == _OP_STATISTICS:
            (message_count,) = _U64.unpack_from(data, a)
    if not channels or message_count is None:
        return None
    extra: list[bytes] = []
    extra_pos = len(data)
    per_channel: dict[int, list[tuple[np.ndarray, np.ndarray]]] = {cid: [] for cid in channels}
    for a, _b in chunk_indexes:
        _start_t, _end_t, chunk_off, _chunk_len = struct.unpack_from("<QQQQ", data, a)
        (map_len,) = _U32.unpack_from(data, a + 32)
        mi = np.frombuffer(data, dtype=np.dtype([("cid", "<u2"), ("off", "<u8")]),
                           count=map_len // 10, offset=a + 36)
        p = a + 36 + map_len
        (_mi_len,) = _U64.unpack_from(data, p)
        compression, p = _string(data, p + 8)
        if data[chunk_off] != _OP_CHUNK:
            return None
        c = chunk_off + 9
        (_usize,) = _U64.unpack_from(data, c + 16)
        ccomp, c = _string(data, c + 28)
        (rec_len,) = _U64.unpack_from(data, c)
        rec_start = c + 8
        if ccomp == "":
            base = rec_start
        else:
            raw = data[rec_start:rec_start + rec_len]
            try:
                if ccomp == "zstd":
                    import zstandard

                    dec = zstandard.ZstdDecompressor().decompress(raw, max_output_size=_usize)
                elif ccomp == "lz4":
                    import lz4.frame

                    dec = lz4.frame.decompress(raw)
                else:
                    return None
            except ImportError:
                return None
            base = extra_pos
            extra.append(dec)
            extra_pos += len(dec)
        for cid, off in zip(mi["cid"].tolist(), mi["off"].tolist()):
            if data[off] != _OP_MESSAGE_INDEX:
                return None
            (rlen,) = _U32.unpack_from(data, off + 9 + 2)
            pairs = np.frombuffer(data, dtype="<u8", count=rlen // 8, offset=off + 9 + 6).reshape(-1, 2)
            if cid in per_channel:
                per_channel[cid].append((pairs[:, 0].astype(np.int64), pairs[:, 1].astype(np.int64) + base))
    if sum(sum(len(p[0]) for p in parts) for parts in per_channel.values()) != message_count:
        return None  # messages outside indexed chunks: let the general reader handle the file
    buf = memoryview(data + b"".join(extra) if extra else data)
    arr = np.frombuffer(buf, dtype=np.uint8)
    topics: dict[str, TopicIndex] = {}
    for cid, (topic, sid, _enc) in channels.items():
        parts = per_channel[cid]
        t = np.concatenate([p[0] for p in parts]) if parts else np.zeros(0, np.int64)
        rec = np.concatenate([p[1] for p in parts]) if parts else np.zeros(0, np.int64)
        order = np.argsort(t, kind="stable")
        t, rec = t[order], rec[order]
        if rec.size:
            if np.any(arr[rec] != _OP_MESSAGE):
                return None
            # record length (u64 at rec+1), little-endian, gathered bytewise
            lens = np.zeros(rec.size, dtype=np.uint64)
            for k in range(8):
                lens |= arr[rec + 1 + k].astype(np.uint64) << np.uint64(8 * k)
            length = lens.astype(np.int64) - 22  # channel id, sequence, log time, publish time
            offset = rec + 9 + 22
            if np.any(length < 0) or np.any(offset + length > arr.size):
                return None   # damaged record lengths: the salvaging reader decides
            logged = np.zeros(rec.size, dtype=np.uint64)
            for k in range(8):
                logged |= arr[rec + 15 + k].astype(np.uint64) << np.uint64(8 * k)
            if np.any(logged.astype(np.int64) != t):
                return None   # index and message disagree: damaged chunk or index
        else:
            length = offset = np.zeros(0, np.int64)
        msgtype = schemas.get(sid, "")
        if topic in topics:  # several channels on one topic: merge
            old = topics[topic]
            t = np.concatenate([old.log_time, t])
            offset = np.concatenate([old.offset, offset])
            length = np.concatenate([old.length, length])
            order = np.argsort(t, kind="stable")
            t, offset, length = t[order], offset[order], length[order]
        topics[topic] = TopicIndex(topic, msgtype, t, offset, length)
    return Index(buf, topics)
