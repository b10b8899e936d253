"""The machine in 3D as visualization_msgs/MarkerArray, ROS-free.

A plant's marker function turns its state arrays into a list of :class:`Marker` (plain data:
type, namespace, id, pose, scale, colour, points, per-point colours) in frame ``world``; this
module turns such a list into the serialised MarkerArray (CDR bytes, the same for a ROS
publisher, which publishes bytes as they are, and for a bag: :func:`marker_array_cdr`) and writes
a series of them into a bag (:func:`write_markers`). Cables are coloured by tension
(:func:`tension_colour`: blue slack, green mid, red at the top of the scale). A machine given as
a MuJoCo model draws itself from its geoms and tendons: :mod:`cablelab.mjcf_markers`.
"""
from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

MARKER_ARRAY = "visualization_msgs/msg/MarkerArray"
#: visualization_msgs/Marker types used here
CUBE, SPHERE, CYLINDER, LINE_STRIP, LINE_LIST, SPHERE_LIST = 1, 2, 3, 4, 5, 7
#: how often the simulators publish the markers (Hz of wall time) and the overlay bag holds them
RATE_HZ = 30.0


@dataclass
class Marker:
    """One marker. ``position`` (3,) and ``quat`` (x, y, z, w) place a shape; ``points`` (k, 3)
    are in ``world`` for lines; ``colours`` (k, 4) per point (RGBA 0..1) or None."""

    type: int
    ns: str
    id: int = 0
    position: tuple = (0.0, 0.0, 0.0)
    quat: tuple = (0.0, 0.0, 0.0, 1.0)
    scale: tuple = (1.0, 1.0, 1.0)
    colour: tuple = (0.7, 0.7, 0.7, 1.0)
    points: np.ndarray | None = None
    colours: np.ndarray | None = field(default=None)


def tension_colour(tension, top: float) -> np.ndarray:
    """RGBA (..., 4) of cable tensions on a blue (0) - green - red (``top`` and above) scale."""
    x = np.clip(np.asarray(tension, dtype=float) / max(float(top), 1e-9), 0.0, 1.0)
    r = np.clip(2.0 * x - 1.0, 0.0, 1.0)
    b = np.clip(1.0 - 2.0 * x, 0.0, 1.0)
    g = 1.0 - r - b
    return np.stack([r, g, b, np.ones_like(x)], axis=-1)


def line(ns: str, id: int, points, colour, width: float = 0.02) -> Marker:
    """A LINE_STRIP through ``points`` (k, 3) in one colour."""
    pts = np.asarray(points, dtype=float).reshape(-1, 3)
    return Marker(LINE_STRIP, ns, id, scale=(width, 0.0, 0.0), colour=tuple(np.asarray(colour, float)),
                  points=pts)


def stamp_parts(t) -> tuple[np.ndarray, np.ndarray]:
    """(sec, nanosec) of times ``t`` (s), rounded to the nanosecond: a time a hair below a whole
    second (0.005 added 400 times) is that second, not the second before with 0 ns."""
    ns = np.round(np.asarray(t, dtype=float).reshape(-1) * 1e9).astype(np.int64)
    return ns // 1_000_000_000, ns % 1_000_000_000


def marker_array_cdr(markers: list[Marker], t: float, frame_id: str = "world") -> bytes:
    """The serialised visualization_msgs/MarkerArray (CDR, as on the wire and in a bag) of
    ``markers`` stamped ``t`` (s). Every marker is ADD with no lifetime (replaced by the next
    array with the same ns/id). Slow and general; a series of arrays of one layout goes through
    :class:`MarkerEncoder`."""
    from . import cdr

    return bytes(cdr.typestore().serialize_cdr(_message(markers, t, frame_id), MARKER_ARRAY))


def _message(markers: list[Marker], t: float, frame_id: str = "world"):
    from . import cdr

    ts = cdr.typestore()
    g = ts.types
    sec, nsec = stamp_parts([t])
    stamp = g["builtin_interfaces/msg/Time"](sec=int(sec[0]), nanosec=int(nsec[0]))

    def colour(c):
        return g["std_msgs/msg/ColorRGBA"](r=float(c[0]), g=float(c[1]), b=float(c[2]), a=float(c[3]))

    def point(p):
        return g["geometry_msgs/msg/Point"](x=float(p[0]), y=float(p[1]), z=float(p[2]))

    out = []
    for m in markers:
        pts = [] if m.points is None else [point(p) for p in np.asarray(m.points, dtype=float)]
        cols = [] if m.colours is None else [colour(c) for c in np.asarray(m.colours, dtype=float)]
        out.append(g["visualization_msgs/msg/Marker"](
            header=g["std_msgs/msg/Header"](stamp=stamp, frame_id=frame_id), ns=m.ns, id=int(m.id),
            type=int(m.type), action=0,
            pose=g["geometry_msgs/msg/Pose"](position=point(m.position), orientation=g["geometry_msgs/msg/Quaternion"](
                x=float(m.quat[0]), y=float(m.quat[1]), z=float(m.quat[2]), w=float(m.quat[3]))),
            scale=g["geometry_msgs/msg/Vector3"](x=float(m.scale[0]), y=float(m.scale[1]), z=float(m.scale[2])),
            color=colour(m.colour),
            lifetime=g["builtin_interfaces/msg/Duration"](sec=0, nanosec=0), frame_locked=False,
            points=pts, colors=cols, texture_resource="",
            texture=g["sensor_msgs/msg/CompressedImage"](
                header=g["std_msgs/msg/Header"](stamp=g["builtin_interfaces/msg/Time"](sec=0, nanosec=0),
                                                 frame_id=""), format="",
                data=np.zeros(0, dtype=np.uint8)),
            uv_coordinates=[], text="", mesh_resource="",
            mesh_file=g["visualization_msgs/msg/MeshFile"](filename="", data=np.zeros(0, dtype=np.uint8)),
            mesh_use_embedded_materials=False))
    return g[MARKER_ARRAY](markers=out)


class MarkerEncoder:
    """Serialise MarkerArrays that share one layout (same markers, same number of points: one
    plant's machine) by patching the numbers of a template serialised once
    (:func:`cablelab.cdr.walk`); vectorised over frames (CPU per array: bench/bench_monitor.py)."""

    def __init__(self, template: list[Marker], frame_id: str = "world"):
        from . import cdr

        self.base = np.frombuffer(marker_array_cdr(template, 0.0, frame_id), dtype=np.uint8).copy()
        spans = cdr.walk(MARKER_ARRAY, bytes(self.base)).spans
        f8, f4, sec, nsec = [], [], [], []
        for k, m in enumerate(template):
            p = f"markers[{k}]"
            sec.append(spans[f"{p}.header.stamp.sec"][0])
            nsec.append(spans[f"{p}.header.stamp.nanosec"][0])
            f8 += [spans[f"{p}.{path}.{ax}"][0] for path, axes in
                   (("pose.position", "xyz"), ("pose.orientation", "xyzw"), ("scale", "xyz")) for ax in axes]
            f4 += [spans[f"{p}.color.{ax}"][0] for ax in "rgba"]
            f8 += [spans[f"{p}.points[{j}].{ax}"][0] for j in range(0 if m.points is None else len(m.points))
                   for ax in "xyz"]
            f4 += [spans[f"{p}.colors[{j}].{ax}"][0] for j in range(0 if m.colours is None else len(m.colours))
                   for ax in "rgba"]
        self.idx = {name: (np.asarray(off)[:, None] + np.arange(size)).ravel()
                    for name, off, size in (("f8", f8, 8), ("f4", f4, 4), ("sec", sec, 4), ("nsec", nsec, 4))}

    @staticmethod
    def values(frame: list[Marker]) -> tuple[np.ndarray, np.ndarray]:
        """(float64 numbers, float32 numbers) of one frame in the encoder's field order."""
        f8, f4 = [], []
        for m in frame:
            f8 += [m.position, m.quat, m.scale]
            f4.append(m.colour)
            if m.points is not None:
                f8.append(np.asarray(m.points, dtype=float).ravel())
            if m.colours is not None:
                f4.append(np.asarray(m.colours, dtype=float).ravel())
        return np.concatenate([np.ravel(a) for a in f8]), np.concatenate([np.ravel(a) for a in f4])

    def encode(self, t, frames) -> list[bytes]:
        """One serialised MarkerArray per time of ``t`` (s) from ``frames`` (lists of markers of
        the template's layout)."""
        t = np.asarray(t, dtype=float).reshape(-1)
        n = len(t)
        mat = np.empty((n, self.base.size), dtype=np.uint8)
        mat[:] = self.base
        vals = [self.values(f) for f in frames]
        sec, nsec = stamp_parts(t)
        k = len(self.idx["sec"]) // 4
        for name, arr, dt in (("f8", np.array([v[0] for v in vals]), "<f8"),
                              ("f4", np.array([v[1] for v in vals]), "<f4"),
                              ("sec", np.repeat(sec[:, None], k, axis=1), "<i4"),
                              ("nsec", np.repeat(nsec[:, None], k, axis=1), "<u4")):
            mat[:, self.idx[name]] = np.ascontiguousarray(arr.astype(dt)).view(np.uint8).reshape(n, -1)
        return [bytes(row) for row in mat]


def _layout(markers: list[Marker]) -> tuple:
    return tuple((m.type, m.ns, m.id, None if m.points is None else len(m.points),
                  None if m.colours is None else len(m.colours)) for m in markers)


def decimate_times(t, rate: float = RATE_HZ) -> np.ndarray:
    """Indices of the samples of ``t`` (s) kept for markers at about ``rate`` Hz."""
    t = np.asarray(t, dtype=float)
    if not len(t):
        return np.zeros(0, dtype=int)
    slot = np.floor((t - t[0]) * rate).astype(np.int64)
    return np.flatnonzero(np.r_[True, slot[1:] != slot[:-1]])


def write_markers(writer, topic: str, t, frames) -> None:
    """Write one MarkerArray per time of ``t`` (``frames``: a list of markers per time) to a
    :class:`~cablelab.bags.BagWriter`."""
    writer.add_topic(topic, MARKER_ARRAY)
    t = np.asarray(t, dtype=float)
    if not len(t):
        return
    enc = MarkerEncoder(frames[0])
    for ti, data in zip(t.tolist(), enc.encode(t, frames)):
        writer.write_raw(topic, int(round(ti * 1e9)), data)


__all__ = ["CUBE", "CYLINDER", "LINE_LIST", "LINE_STRIP", "MARKER_ARRAY", "Marker", "MarkerEncoder", "RATE_HZ", "SPHERE",
           "SPHERE_LIST", "decimate_times", "line", "marker_array_cdr", "stamp_parts", "tension_colour",
           "write_markers"]
