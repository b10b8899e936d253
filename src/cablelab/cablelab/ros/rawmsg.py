"""Pre-serialised outgoing messages: serialise once, patch the numbers in place, publish bytes.

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

__all__ = ["RawTemplate", "type_name"]


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
