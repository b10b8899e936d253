"""Serialised messages both ways: pre-serialised outgoing messages (serialise once, patch the
numbers in place, publish bytes) and incoming bytes decoded without rclpy message objects
(:class:`RawReader`).

Building an rclpy message object per sample and letting rclpy convert and serialise it costs
30-60 us of CPU for a JointState or a MultiDOFJointTrajectory; a 1 kHz node publishing three of
them spends most of its time there. A stream whose *layout* never changes (same joint names,
same array lengths, same frame id: only stamps and values move) can instead keep its serialised
CDR bytes and overwrite the numeric fields through numpy views, then hand the bytes to
``Publisher.publish`` (rclpy publishes ``bytes`` as an already serialised message).

The byte offsets come from :func:`cablelab.cdr.walk` on the message serialised by rclpy itself
(``rclpy.serialization.serialize_message``), so the template is exactly what rclpy would have
sent; the tests check every patched template against ``deserialize_message``.

    tpl = RawTemplate(convert.joint_state_msg(0.0, names, zeros, zeros, zeros))
    tpl.stamp(t)
    tpl["position"][:] = q
    pub.publish(tpl.data())
"""
from __future__ import annotations

import struct

import numpy as np

from .. import cdr
from . import convert

__all__ = ["RawTemplate", "CommandTemplate", "RawReader", "type_name", "joint_state_arrays", "multidof_arrays", "command_arrays"]


def type_name(cls) -> str:
    """``'pkg/msg/Name'`` of an rclpy message class."""
    return f"{cls.__module__.split('.')[0]}/msg/{cls.__name__}"


class RawTemplate:
    """Serialised bytes of ``msg`` with writable numpy views on its numeric fields.

    Args:
        msg: an rclpy message with the final structure (strings, sequence lengths); its numbers
            are only initial values.

    Views: ``tpl[path]`` is the writable float64/int array of one numeric field, by the paths of
    :func:`cablelab.cdr.walk` (``"effort"``, ``"header.stamp.sec"``, ``"inertia.m"``,
    ``"points[0].transforms[0].translation.x"``); :meth:`vector` joins consecutive scalar
    fields (x, y, z) into one (3,) view.
    """

    def __init__(self, msg):
        from rclpy.serialization import serialize_message

        self.msg_type = type(msg)
        self.type_name = type_name(self.msg_type)
        raw = serialize_message(msg)
        layout = cdr.walk(self.type_name, raw)
        self.buf = bytearray(raw)
        self.size = len(raw)
        self.spans = dict(layout.spans)
        self._views: dict[str, np.ndarray] = {}

    def __getitem__(self, path: str) -> np.ndarray:
        view = self._views.get(path)
        if view is None:
            try:
                off, count, dt = self.spans[path]
            except KeyError:
                raise KeyError(f"{self.type_name} has no numeric field {path!r} in this layout "
                               f"(empty sequence?)") from None
            view = np.frombuffer(self.buf, dtype=dt, count=count, offset=off)
            self._views[path] = view
        return view

    def vector(self, prefix: str, fields: str = "xyz") -> np.ndarray:
        """One writable view on the consecutive scalar fields ``prefix.x``, ``prefix.y``, ...
        (e.g. ``"pose.position"``; ``fields="xyzw"`` for a quaternion)."""
        key = f"{prefix}.[{fields}]"
        view = self._views.get(key)
        if view is None:
            spans = [self.spans[f"{prefix}.{f}"] for f in fields]
            off, _, dt = spans[0]
            size = int(dt[-1])
            if any(s[0] != off + i * size or s[1] != 1 or s[2] != dt for i, s in enumerate(spans)):
                raise ValueError(f"{self.type_name}: fields {prefix}.{{{fields}}} are not contiguous")
            view = np.frombuffer(self.buf, dtype=dt, count=len(fields), offset=off)
            self._views[key] = view
        return view

    def stamp(self, t: float, path: str = "header.stamp") -> None:
        """Write time t (s) into a builtin_interfaces/Time field (nanosecond rounding)."""
        ns = int(round(t * 1e9))
        self[path + ".sec"][0] = ns // 1_000_000_000
        self[path + ".nanosec"][0] = ns % 1_000_000_000

    def text_offset(self, text: str) -> int:
        """Byte offset of the unique occurrence of ``text`` in the serialised message (to patch
        a string with another of the same length, :meth:`write_text`)."""
        b = text.encode()
        off = self.buf.find(b)
        if off < 0 or self.buf.find(b, off + 1) >= 0:
            raise ValueError(f"{self.type_name}: text {text!r} not found exactly once")
        return off

    def write_text(self, offset: int, text: str) -> None:
        b = text.encode()
        self.buf[offset:offset + len(b)] = b

    def data(self) -> bytes:
        """The serialised message as it is now (a copy: safe to publish and keep patching)."""
        return bytes(self.buf)


class CommandTemplate:
    """Serialised effort commands that name the state they answer (:func:`convert.command_msg`:
    data = the efforts, ``layout.dim[0].label = '<label> stamp=<t>'``), from one
    :class:`RawTemplate` per label length and command length (only the digits and the numbers
    change from one command to the next)."""

    def __init__(self, label: str = "command"):
        self.label = label
        self._templates: dict = {}

    def data(self, command, stamp: float) -> bytes:
        """The serialised command ``command`` (n,) answering the state of ``stamp`` (s)."""
        from std_msgs.msg import MultiArrayDimension

        label = f"{self.label} stamp={float(stamp):.9f}"
        key = (len(label), len(command))
        entry = self._templates.get(key)
        if entry is None:
            msg = convert.float_array_msg(command)
            msg.layout.dim = [MultiArrayDimension(label=label, size=len(command), stride=len(command))]
            tpl = RawTemplate(msg)
            entry = self._templates[key] = (tpl, tpl["data"], tpl.text_offset(label))
        tpl, values, off = entry
        values[:] = command
        tpl.write_text(off, label)
        return tpl.data()


class RawReader:
    """Decode incoming serialised messages of one type without building rclpy message objects.

    rclpy's conversion of a received ``MultiDOFJointTrajectory`` into Python objects costs about
    30 us of CPU (a ``JointState`` of 8 joints about 15 us); a 1 kHz controller taking a state
    and a reference per cycle spent a third of its time there. A stream keeps its *layout* (names,
    sequence lengths, frame id) from sample to sample, so the layout is parsed once
    (:func:`cablelab.cdr.walk`) and reused while the bytes that fix it (everything but the
    numeric values and the alignment padding, :meth:`cablelab.cdr.Layout.numeric_mask`) stay the
    same: they are compared as a few byte runs, a microsecond per message; the numbers are then
    read through :func:`numpy.frombuffer` at known offsets. A message with another layout is
    parsed anew; bytes that are not a valid message raise ``ValueError``.

    Args:
        msg_type: the rclpy message class (e.g. ``sensor_msgs.msg.JointState``).

    Attributes:
        memo: per-layout cache of the decoding functions (what they derive from the layout once,
            e.g. the joint names); emptied when the layout changes.
    """

    def __init__(self, msg_type):
        self.type_name = type_name(msg_type)
        self._layout = None
        self._size = -1
        self._runs = ()         # (start, end, bytes) of every run of layout-fixing bytes
        self.memo: dict = {}
        self.parsed = 0         # layouts parsed (1 for a well-behaved stream)

    def layout(self, raw) -> cdr.Layout:
        """The :class:`cablelab.cdr.Layout` of ``raw`` (cached while the structure repeats)."""
        lay = self._layout
        if lay is not None and len(raw) == self._size:
            for a, b, want in self._runs:
                if raw[a:b] != want:
                    break
            else:
                return lay
        buf = bytes(raw)
        lay = cdr.walk(self.type_name, buf)
        keep = ~lay.numeric_mask()
        edges = np.flatnonzero(np.diff(np.concatenate(([False], keep, [False])).astype(np.int8)))
        self._runs = tuple((int(a), int(b), buf[a:b]) for a, b in zip(edges[::2], edges[1::2]))
        self._size = len(buf)
        self._layout = lay
        self.memo = {}
        self.parsed += 1
        return lay

    @staticmethod
    def values(raw, lay: cdr.Layout, path: str) -> np.ndarray | None:
        """float64 copy of a numeric field (None when the field is an empty sequence)."""
        span = lay.spans.get(path)
        if span is None:
            return None
        off, count, dt = span
        return np.frombuffer(raw, dtype=dt, count=count, offset=off).astype(np.float64)

    @staticmethod
    def stamp(raw, lay: cdr.Layout, path: str = "header.stamp") -> float:
        """A builtin_interfaces/Time field in s."""
        off, _, dt = lay.spans[path + ".sec"]
        sec = int(np.frombuffer(raw, dtype=dt, count=1, offset=off)[0])
        off, _, dt = lay.spans[path + ".nanosec"]
        return sec + int(np.frombuffer(raw, dtype=dt, count=1, offset=off)[0]) * 1e-9

    @staticmethod
    def stamp_reader(lay: cdr.Layout, path: str = "header.stamp"):
        """``read(raw) -> s`` of a builtin_interfaces/Time field of this layout (int32 sec and
        uint32 nanosec, consecutive): one ``struct`` unpack per message."""
        off, _, dt = lay.spans[path + ".sec"]
        fmt = struct.Struct(dt[0] + "iI")

        def read(raw) -> float:
            sec, nsec = fmt.unpack_from(raw, off)
            return sec + nsec * 1e-9

        return read


def _raw(msg) -> bool:
    return isinstance(msg, (bytes, bytearray, memoryview))


def _field(lay: cdr.Layout, path: str):
    """``read(raw) -> float64 copy`` of a numeric field of this layout, or None when absent."""
    span = lay.spans.get(path)
    if span is None:
        return None
    off, count, dt = span
    frombuffer, f8 = np.frombuffer, np.float64

    def read(raw) -> np.ndarray:
        return frombuffer(raw, dtype=dt, count=count, offset=off).astype(f8)

    return read


def _joint_state_plan(lay: cdr.Layout):
    names = [lay.strings[f"name[{i}]"] for i in range(lay.seqlen.get("name", 0))]
    return (RawReader.stamp_reader(lay), names, _field(lay, "position"), _field(lay, "velocity"),
            _field(lay, "effort"))


def joint_state_arrays(msg, reader: RawReader):
    """:func:`cablelab.ros.convert.joint_state_arrays` of a JointState message object or of its
    serialised bytes (decoded by ``reader``): (t s, names, position, velocity, effort), None for
    empty fields. Raises ValueError for bytes that are not a JointState."""
    if not _raw(msg):
        return convert.joint_state_arrays(msg)
    lay = reader.layout(msg)
    plan = reader.memo.get("joint_state")
    if plan is None:
        plan = reader.memo["joint_state"] = _joint_state_plan(lay)
    stamp, names, pos, vel, eff = plan
    return (stamp(msg), list(names), None if pos is None else pos(msg), None if vel is None else vel(msg),
            None if eff is None else eff(msg))


_P0 = "points[0]."


def _multidof_plan(lay: cdr.Layout):
    """(stamp reader, [(keys, split, offset, count, dtype)]): the first point's translation and
    rotation (7 consecutive float64), its linear and angular velocity, its linear and angular
    acceleration (6 each), each block read with one ``frombuffer`` and split at ``split``."""
    spans = lay.spans
    blocks = []
    if _P0 + "transforms[0].translation.x" in spans:
        blocks.append((("position", "quaternion"), _P0 + "transforms[0].translation",
                       _P0 + "transforms[0].rotation", "xyzw"))
        for fld, name in (("velocities", "velocity"), ("accelerations", "acceleration")):
            if f"{_P0}{fld}[0].linear.x" in spans:
                blocks.append(((f"linear_{name}", f"angular_{name}"), f"{_P0}{fld}[0].linear",
                               f"{_P0}{fld}[0].angular", "xyz"))
    plan = []
    for keys, first, second, f2 in blocks:
        offs = [spans[f"{first}.{c}"] for c in "xyz"] + [spans[f"{second}.{c}"] for c in f2]
        off, _, dt = offs[0]
        if any(o != off + 8 * i or d != dt for i, (o, _, d) in enumerate(offs)):
            raise ValueError(f"{lay.size}-byte MultiDOFJointTrajectory: {first} and {second} not contiguous")
        plan.append((keys, 3, off, len(offs), dt))
    return RawReader.stamp_reader(lay), plan


def multidof_arrays(msg, reader: RawReader) -> dict:
    """:func:`cablelab.ros.convert.multidof_arrays` of a MultiDOFJointTrajectory message object or
    of its serialised bytes (first point, first joint; None where absent)."""
    if not _raw(msg):
        return convert.multidof_arrays(msg)
    lay = reader.layout(msg)
    plan = reader.memo.get("multidof")
    if plan is None:
        plan = reader.memo["multidof"] = _multidof_plan(lay)
    stamp, blocks = plan
    out = {"t": stamp(msg), "position": None, "quaternion": None,
           "linear_velocity": None, "angular_velocity": None,
           "linear_acceleration": None, "angular_acceleration": None}
    for (a, b), split, off, count, dt in blocks:
        v = np.frombuffer(msg, dtype=dt, count=count, offset=off).astype(np.float64)
        out[a], out[b] = v[:split], v[split:]
    return out


def inertia_arrays(msg, reader: RawReader) -> tuple[float, float, np.ndarray]:
    """:func:`cablelab.ros.convert.inertia_arrays` (t s, m kg, com (3,) m) of an InertiaStamped
    message object or of its serialised bytes."""
    if not _raw(msg):
        return convert.inertia_arrays(msg)
    lay = reader.layout(msg)
    plan = reader.memo.get("inertia")
    if plan is None:
        spans = [lay.spans[f"inertia.{k}"] for k in ("m", "com.x", "com.y", "com.z")]
        off, _, dt = spans[0]
        if [(o, d) for o, _, d in spans] != [(off + 8 * i, dt) for i in range(4)]:
            raise ValueError("not a CDR-serialised InertiaStamped")     # (XCDR packs four doubles)
        plan = reader.memo["inertia"] = (RawReader.stamp_reader(lay), struct.Struct(dt[0] + "4d"), off)
    stamp, four, off = plan
    m, *com = four.unpack_from(msg, off)
    return stamp(msg), m, np.array(com)


_U32 = {"<": struct.Struct("<I"), ">": struct.Struct(">I")}


def command_arrays(msg) -> tuple[np.ndarray, float | None]:
    """(data (n,) float64, stamp s of the state it answers or None) of an effort command
    (std_msgs/Float64MultiArray, :func:`cablelab.ros.convert.command_msg`), as a message object or
    its serialised bytes.

    The command's label carries the answered stamp as text, so its bytes change with every
    sample and a cached :class:`RawReader` layout would be re-parsed each time; the layout of
    this one type is short, so it is read directly (XCDR1, either byte order: the 4-byte
    encapsulation header, then ``layout.dim`` = uint32 count of {string label, uint32 size,
    uint32 stride}, uint32 ``data_offset``, uint32 count of float64 ``data`` aligned to 8 from
    the end of the header). Raises ValueError for bytes that are not such a message."""
    if not _raw(msg):
        return convert.float_array(msg), convert.command_stamp(msg)
    b = bytes(msg)
    n = len(b)
    if n < 12 or b[0] != 0 or b[1] not in (0, 1):
        raise ValueError("not a CDR-serialised Float64MultiArray")
    order = "<" if b[1] == 1 else ">"
    u32 = _U32[order].unpack_from
    pos = 4

    def word() -> int:
        nonlocal pos
        pos += -(pos - 4) % 4
        if pos + 4 > n:
            raise ValueError("Float64MultiArray bytes end inside a field")
        v = u32(b, pos)[0]
        pos += 4
        return v

    labels = []
    ndim = word()
    if ndim > 64:
        raise ValueError(f"Float64MultiArray with {ndim} layout dimensions")
    for _ in range(ndim):
        length = word()
        if length < 1 or pos + length > n:
            raise ValueError("Float64MultiArray label runs past the end")
        labels.append(b[pos:pos + length - 1].decode("utf-8", "replace"))
        pos += length
        word()
        word()
    word()                                          # data_offset
    count = word()
    pos += -(pos - 4) % 8
    if pos + 8 * count > n:
        raise ValueError("Float64MultiArray data runs past the end")
    data = np.frombuffer(b, np.dtype(order + "f8"), count, pos).astype(np.float64)
    return data, convert.label_stamp(labels[0]) if labels else None
