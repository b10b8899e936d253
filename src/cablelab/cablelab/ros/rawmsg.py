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
    numeric values, :meth:`cablelab.cdr.Layout.numeric_mask`) stay the same; the numbers are then
    read through :func:`numpy.frombuffer` at known offsets. A message with another layout is
    parsed anew; bytes that are not a valid message raise ``ValueError``.

    Args:
        msg_type: the rclpy message class (e.g. ``sensor_msgs.msg.JointState``).
    """

    def __init__(self, msg_type):
        self.type_name = type_name(msg_type)
        self._layout = None
        self._keep = None
        self._struct = None
        self.parsed = 0         # layouts parsed (1 for a well-behaved stream)

    def layout(self, raw) -> cdr.Layout:
        """The :class:`cablelab.cdr.Layout` of ``raw`` (cached while the structure repeats)."""
        lay = self._layout
        a = np.frombuffer(raw, dtype=np.uint8)
        if lay is not None and a.size == lay.size and np.array_equal(a[self._keep], self._struct):
            return lay
        lay = cdr.walk(self.type_name, bytes(raw))
        self._keep = np.flatnonzero(~lay.numeric_mask())
        self._struct = a[self._keep].copy()
        self._layout = lay
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


def _raw(msg) -> bool:
    return isinstance(msg, (bytes, bytearray, memoryview))


def joint_state_arrays(msg, reader: RawReader):
    """:func:`cablelab.ros.convert.joint_state_arrays` of a JointState message object or of its
    serialised bytes (decoded by ``reader``): (t s, names, position, velocity, effort), None for
    empty fields. Raises ValueError for bytes that are not a JointState."""
    if not _raw(msg):
        return convert.joint_state_arrays(msg)
    lay = reader.layout(msg)
    names = [lay.strings[f"name[{i}]"] for i in range(lay.seqlen.get("name", 0))]
    v = reader.values
    return reader.stamp(msg, lay), names, v(msg, lay, "position"), v(msg, lay, "velocity"), v(msg, lay, "effort")


_P0 = "points[0]."


def multidof_arrays(msg, reader: RawReader) -> dict:
    """:func:`cablelab.ros.convert.multidof_arrays` of a MultiDOFJointTrajectory message object or
    of its serialised bytes (first point, first joint; None where absent)."""
    if not _raw(msg):
        return convert.multidof_arrays(msg)
    lay = reader.layout(msg)
    out = {"t": reader.stamp(msg, lay), "position": None, "quaternion": None,
           "linear_velocity": None, "angular_velocity": None,
           "linear_acceleration": None, "angular_acceleration": None}
    spans = lay.spans
    if _P0 + "transforms[0].translation.x" not in spans:
        return out

    def vec(prefix: str, fields: str = "xyz") -> np.ndarray:
        off, _, dt = spans[f"{prefix}.{fields[0]}"]
        return np.frombuffer(msg, dtype=dt, count=len(fields), offset=off).astype(np.float64)

    out["position"] = vec(_P0 + "transforms[0].translation")
    out["quaternion"] = vec(_P0 + "transforms[0].rotation", "xyzw")
    for field, prefix in (("velocities", "velocity"), ("accelerations", "acceleration")):
        if f"{_P0}{field}[0].linear.x" in spans:
            out[f"linear_{prefix}"] = vec(f"{_P0}{field}[0].linear")
            out[f"angular_{prefix}"] = vec(f"{_P0}{field}[0].angular")
    return out


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
    u32 = np.dtype(order + "u4")
    pos = 4

    def word() -> int:
        nonlocal pos
        pos += -(pos - 4) % 4
        if pos + 4 > n:
            raise ValueError("Float64MultiArray bytes end inside a field")
        v = int(np.frombuffer(b, u32, 1, pos)[0])
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
