"""Writing rosbag2 MCAP bags: :class:`BagWriter` writes whole numpy time series per call,
vectorised with :mod:`cablelab.cdr`, plus already-serialised messages (the recorder)."""
from __future__ import annotations

import shutil
from pathlib import Path

import numpy as np

from .. import cdr
from ..errors import CablelabError
from .reader import _bag_error
from .series import (CLOCK, CLOCK_TOPIC, DESCRIPTION_TOPIC, FLOAT64_MULTI_ARRAY, INERTIA_STAMPED,
                     JOINT_STATE, JOINT_TRAJECTORY, MULTIDOF_TRAJECTORY, POSE_STAMPED, STRING)


def qos_profile(transient_local: bool = False, depth: int = 1):
    """A rosbags Qos for the offered_qos_profiles of a topic (reliable, keep-last)."""
    from rosbags.interfaces import Qos, QosDurability, QosHistory, QosLiveliness, QosReliability, QosTime

    inf = QosTime(sec=9223372036, nsec=854775807)
    return Qos(
        history=QosHistory.KEEP_LAST,
        depth=depth,
        reliability=QosReliability.RELIABLE,
        durability=QosDurability.TRANSIENT_LOCAL if transient_local else QosDurability.VOLATILE,
        deadline=inf,
        lifespan=inf,
        liveliness=QosLiveliness.AUTOMATIC,
        liveliness_lease_duration=inf,
        avoid_ros_namespace_conventions=False,
    )


def _ns(t) -> np.ndarray:
    t = np.asarray(t, dtype=float).reshape(-1)
    if not np.all(np.isfinite(t)):
        raise CablelabError("bag writer: times must be finite numbers")
    return np.round(t * 1e9).astype(np.int64)


def _sec_nsec(ns: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    sec = np.floor_divide(ns, 1_000_000_000)
    return sec.astype(np.int32), (ns - sec * 1_000_000_000).astype(np.uint32)


def _stamp_fills(ns: np.ndarray, prefix: str = "header.stamp") -> dict:
    """cdr.encode fills of a builtin_interfaces/Time field from stamps ``ns`` (int64 ns)."""
    sec, nsec = _sec_nsec(ns)
    return {f"{prefix}.sec": sec, f"{prefix}.nanosec": nsec}


def _axes_fills(prefix: str, a: np.ndarray, axes: str = "xyz") -> dict:
    """cdr.encode fills ``{prefix}.x, .y, ...`` from the columns of ``a`` (N, len(axes))."""
    return {f"{prefix}.{ax}": a[:, i] for i, ax in enumerate(axes)}


def _as2d(a, n: int, k: int | None, what: str) -> np.ndarray | None:
    """a as an (n, k) float array (1-D input is taken as n rows); None stays None."""
    if a is None:
        return None
    a = np.asarray(a, dtype=float)
    try:
        if a.ndim == 1:
            a = a.reshape(n, -1)
        ok = a.ndim == 2 and a.shape[0] == n and (k is None or a.shape[1] == k)
    except ValueError:
        ok = False
    if not ok:
        want = f"({n}, {k})" if k is not None else f"({n}, k)"
        raise CablelabError(f"bag writer: {what} has shape {np.shape(a)}, expected {want}")
    return a


class BagWriter:
    """Write a rosbag2 MCAP bag (directory) from numpy time series.

    Use as a context manager; the bag (metadata.yaml and MCAP footer) is complete on exit.
    Times ``t`` are in seconds and become both the header stamp and the log time (``log_time``
    may give another log time, e.g. the receive time).

    Args:
        path: bag directory to create
        overwrite: replace an existing bag directory cablelab wrote (it carries the marker
            :data:`cablelab.atomic.MARKER`, written into every bag on open); without it an
            existing path is an error and nothing is touched. Anything else (a bag of another
            recorder, a user's directory, a file) is never replaced.
    """

    def __init__(self, path, overwrite: bool = False):
        self.path = Path(path)
        if self.path.suffix == ".mcap":
            raise _bag_error(self.path, "give a bag directory name, not a .mcap file name")
        if self.path.exists():
            if not overwrite:
                raise _bag_error(self.path, "exists already (use --overwrite to replace it)")
            from ..atomic import MARKER, replaceable

            if not replaceable(self.path):
                raise _bag_error(self.path, f"exists and is not a bag cablelab wrote (no {MARKER}); "
                                            f"not overwriting it")
            if self.path.is_dir():
                shutil.rmtree(self.path)
            else:
                self.path.unlink()
        self._writer = None
        self._conns: dict[str, object] = {}
        self.counts: dict[str, int] = {}

    # ---- lifecycle
    def open(self) -> "BagWriter":
        from rosbags.rosbag2 import StoragePlugin, Writer

        if not self.path.parent.exists():
            raise _bag_error(self.path, f"parent directory {self.path.parent} does not exist")
        from ..atomic import write_marker

        self._writer = Writer(self.path, version=9, storage_plugin=StoragePlugin.MCAP)
        self._writer.open()
        write_marker(self.path, "bag")   # what cablelab wrote, it may replace with overwrite
        return self

    def close(self) -> None:
        if self._writer is not None:
            self._writer.close()
            self._writer = None
            import contextlib

            from ..atomic import write_marker

            with contextlib.suppress(OSError):   # (full disk: the marker of open() stays)
                write_marker(self.path, "bag")   # now also listing metadata.yaml

    def __enter__(self) -> "BagWriter":
        return self.open()

    def __exit__(self, exc_type, exc, tb) -> bool:
        self.close()
        return False

    def flush(self) -> None:
        """Write buffered messages to disk as a complete MCAP chunk (survives a later SIGKILL
        up to this point; see docs/bags.md)."""
        storage = getattr(self._writer, "storage", None)
        if storage is not None:
            if storage.chunk.bio.tell():
                storage.close_chunk()
            storage.bio.flush()

    # ---- generic
    def add_topic(self, topic: str, msgtype: str, *, transient_local: bool = False):
        """Register a topic (idempotent); CablelabError if it exists with another type."""
        if self._writer is None:
            self.open()
        conn = self._conns.get(topic)
        if conn is not None:
            if conn.msgtype != msgtype:
                raise CablelabError(f"{self.path}: topic {topic} already has type {conn.msgtype}, "
                                    f"cannot write {msgtype}")
            return conn
        ts = cdr.typestore()
        if msgtype not in ts.fielddefs:
            raise CablelabError(f"{self.path}: topic {topic}: unknown message type {msgtype}")
        conn = self._writer.add_connection(
            topic, msgtype, typestore=ts,
            offered_qos_profiles=[qos_profile(transient_local=transient_local)])
        self._conns[topic] = conn
        self.counts[topic] = 0
        return conn

    def set_custom_data(self, key: str, value: str) -> None:
        """A key/value of metadata.yaml's ``custom_data`` (written when the bag is closed)."""
        if self._writer is None:
            self.open()
        self._writer.set_custom_data(str(key), str(value))

    def write_raw(self, topic: str, t_ns: int, data: bytes) -> None:
        """Write one already-serialised CDR message (topic registered with :meth:`add_topic`)."""
        self._writer.write(self._conns[topic], int(t_ns), data)
        self.counts[topic] += 1

    def _write_batch(self, topic: str, msgtype: str, log_ns: np.ndarray, flat: np.ndarray, L: int,
                     transient_local: bool = False) -> None:
        conn = self.add_topic(topic, msgtype, transient_local=transient_local)
        write = self._writer.write
        mv = memoryview(flat)
        for i, stamp in enumerate(log_ns.tolist()):
            write(conn, stamp, mv[i * L:(i + 1) * L])
        self.counts[topic] += len(log_ns)

    def _write_encoded(self, topic: str, msgtype: str, tmpl, fills: dict, log_ns: np.ndarray) -> None:
        """Encode one message per log time from the template and its per-message field values
        (:func:`cablelab.cdr.encode`) and write them."""
        flat, L = cdr.encode(msgtype, tmpl, fills, len(log_ns))
        self._write_batch(topic, msgtype, log_ns, flat, L)

    def write_messages(self, topic: str, msgtype: str, t, msgs, transient_local: bool = False) -> None:
        """Write rosbags message objects one by one (slow, general)."""
        ts = cdr.typestore()
        conn = self.add_topic(topic, msgtype, transient_local=transient_local)
        for stamp, msg in zip(_ns(t).tolist(), msgs):
            self._writer.write(conn, stamp, ts.serialize_cdr(msg, msgtype))
            self.counts[topic] += 1

    # ---- typed batch writers
    def _header(self, frame_id: str = ""):
        ts = cdr.typestore()
        return ts.types["std_msgs/msg/Header"](
            stamp=ts.types["builtin_interfaces/msg/Time"](sec=0, nanosec=0), frame_id=frame_id)

    def _log(self, ns: np.ndarray, log_time) -> np.ndarray:
        if log_time is None:
            return ns
        log = _ns(log_time)
        if log.shape != ns.shape:
            raise CablelabError(f"bag writer: log_time has {log.size} values, t has {ns.size}")
        return log

    def write_description(self, yaml_text: str, t: float = 0.0) -> None:
        """/plant_description (std_msgs/String, transient-local) holding the YAML text."""
        self.write_strings(DESCRIPTION_TOPIC, [t], [yaml_text], transient_local=True)

    def write_strings(self, topic: str, t, texts, transient_local: bool = False) -> None:
        """std_msgs/String messages (log time t)."""
        ts = cdr.typestore()
        S = ts.types[STRING]
        ns = _ns(t)
        texts = list(texts)
        if len(texts) != len(ns):
            raise CablelabError(f"bag writer: {topic}: {len(texts)} texts for {len(ns)} times")
        conn = self.add_topic(topic, STRING, transient_local=transient_local)
        for stamp, text in zip(ns.tolist(), texts):
            self._writer.write(conn, stamp, ts.serialize_cdr(S(data=str(text)), STRING))
        self.counts[topic] += len(ns)

    def write_clock(self, t, topic: str = CLOCK_TOPIC) -> None:
        """rosgraph_msgs/Clock messages holding t (s), logged at t."""
        ts = cdr.typestore()
        ns = _ns(t)
        tmpl = ts.types[CLOCK](clock=ts.types["builtin_interfaces/msg/Time"](sec=0, nanosec=0))
        self._write_encoded(topic, CLOCK, tmpl, _stamp_fills(ns, "clock"), ns)

    def write_joint_states(self, topic: str, t, names, position=None, velocity=None, effort=None,
                           *, frame_id: str = "", log_time=None) -> None:
        """sensor_msgs/JointState messages: t (N,) s, arrays (N, k) in the order of ``names``;
        a field given as None is written empty."""
        ts = cdr.typestore()
        ns = _ns(t)
        n, k = len(ns), len(names)
        arrays = {f: _as2d(a, n, k, f"{topic} {f}") for f, a in
                  (("position", position), ("velocity", velocity), ("effort", effort))}
        tmpl = ts.types[JOINT_STATE](
            header=self._header(frame_id), name=[str(x) for x in names],
            **{f: np.zeros(0 if a is None else k) for f, a in arrays.items()})
        fills = _stamp_fills(ns)
        fills.update({f: a for f, a in arrays.items() if a is not None and k})
        self._write_encoded(topic, JOINT_STATE, tmpl, fills, self._log(ns, log_time))

    def write_poses(self, topic: str, t, position, quaternion, frame_id: str = "world", *,
                    log_time=None) -> None:
        """geometry_msgs/PoseStamped: position (N, 3) m, quaternion (N, 4) x, y, z, w."""
        ts = cdr.typestore()
        ns = _ns(t)
        n = len(ns)
        p = _as2d(position, n, 3, f"{topic} position")
        q = _as2d(quaternion, n, 4, f"{topic} quaternion")
        g = ts.types
        tmpl = g[POSE_STAMPED](header=self._header(frame_id), pose=g["geometry_msgs/msg/Pose"](
            position=g["geometry_msgs/msg/Point"](x=0.0, y=0.0, z=0.0),
            orientation=g["geometry_msgs/msg/Quaternion"](x=0.0, y=0.0, z=0.0, w=1.0)))
        fills = {**_stamp_fills(ns), **_axes_fills("pose.position", p),
                 **_axes_fills("pose.orientation", q, "xyzw")}
        self._write_encoded(topic, POSE_STAMPED, tmpl, fills, self._log(ns, log_time))

    def write_inertia(self, topic: str, t, m, com, frame_id: str = "platform", *,
                      log_time=None) -> None:
        """geometry_msgs/InertiaStamped: mass m (N,) kg, centre of mass com (N, 3) m."""
        ts = cdr.typestore()
        ns = _ns(t)
        n = len(ns)
        m = _as2d(m, n, 1, f"{topic} m")
        c = _as2d(com, n, 3, f"{topic} com")
        g = ts.types
        tmpl = g[INERTIA_STAMPED](header=self._header(frame_id), inertia=g["geometry_msgs/msg/Inertia"](
            m=0.0, com=g["geometry_msgs/msg/Vector3"](x=0.0, y=0.0, z=0.0),
            ixx=0.0, ixy=0.0, ixz=0.0, iyy=0.0, iyz=0.0, izz=0.0))
        fills = {**_stamp_fills(ns), "inertia.m": m, **_axes_fills("inertia.com", c)}
        self._write_encoded(topic, INERTIA_STAMPED, tmpl, fills, self._log(ns, log_time))

    def write_float_arrays(self, topic: str, t, data) -> None:
        """std_msgs/Float64MultiArray: data (N, k), logged at t (the message has no header)."""
        ts = cdr.typestore()
        ns = _ns(t)
        n = len(ns)
        d = _as2d(data, n, None, f"{topic} data")
        k = d.shape[1]
        g = ts.types
        tmpl = g[FLOAT64_MULTI_ARRAY](layout=g["std_msgs/msg/MultiArrayLayout"](dim=[], data_offset=0),
                                      data=np.zeros(k))
        self._write_encoded(topic, FLOAT64_MULTI_ARRAY, tmpl, {"data": d} if k else {}, ns)

    def write_joint_trajectory(self, topic: str, t, names, positions, velocities=None,
                               accelerations=None, *, log_time=None) -> None:
        """trajectory_msgs/JointTrajectory with one point per message: arrays (N, k)."""
        ts = cdr.typestore()
        ns = _ns(t)
        n, k = len(ns), len(names)
        arrays = {f: _as2d(a, n, k, f"{topic} {f}") for f, a in
                  (("positions", positions), ("velocities", velocities),
                   ("accelerations", accelerations))}
        g = ts.types
        point = g["trajectory_msgs/msg/JointTrajectoryPoint"](
            effort=np.zeros(0), time_from_start=g["builtin_interfaces/msg/Duration"](sec=0, nanosec=0),
            **{f: np.zeros(0 if a is None else k) for f, a in arrays.items()})
        tmpl = g[JOINT_TRAJECTORY](header=self._header(""), joint_names=[str(x) for x in names],
                                   points=[point])
        fills = _stamp_fills(ns)
        fills.update({f"points[0].{f}": a for f, a in arrays.items() if a is not None and k})
        self._write_encoded(topic, JOINT_TRAJECTORY, tmpl, fills, self._log(ns, log_time))

    def write_multidof_trajectory(self, topic: str, t, position, quaternion, linear_velocity=None,
                                  angular_velocity=None, linear_acceleration=None,
                                  angular_acceleration=None, *, joint_name: str = "platform",
                                  log_time=None) -> None:
        """trajectory_msgs/MultiDOFJointTrajectory, one joint and one point per message:
        position (N, 3), quaternion (N, 4) x, y, z, w, velocities/accelerations (N, 3). The
        twist (or acceleration) is written if either of its parts is given (the other as 0)."""
        ts = cdr.typestore()
        ns = _ns(t)
        n = len(ns)
        g = ts.types
        p = _as2d(position, n, 3, f"{topic} position")
        q = _as2d(quaternion, n, 4, f"{topic} quaternion")
        lv, av, la, aa = (_as2d(a, n, 3, f"{topic} {w}") for a, w in (
            (linear_velocity, "linear_velocity"), (angular_velocity, "angular_velocity"),
            (linear_acceleration, "linear_acceleration"), (angular_acceleration, "angular_acceleration")))

        def vec():
            return g["geometry_msgs/msg/Vector3"](x=0.0, y=0.0, z=0.0)

        def twist():
            return g["geometry_msgs/msg/Twist"](linear=vec(), angular=vec())

        has_vel = lv is not None or av is not None
        has_acc = la is not None or aa is not None
        point = g["trajectory_msgs/msg/MultiDOFJointTrajectoryPoint"](
            transforms=[g["geometry_msgs/msg/Transform"](
                translation=vec(), rotation=g["geometry_msgs/msg/Quaternion"](x=0.0, y=0.0, z=0.0, w=1.0))],
            velocities=[twist()] if has_vel else [], accelerations=[twist()] if has_acc else [],
            time_from_start=g["builtin_interfaces/msg/Duration"](sec=0, nanosec=0))
        tmpl = g[MULTIDOF_TRAJECTORY](header=self._header("world"), joint_names=[joint_name],
                                      points=[point])
        fills = {**_stamp_fills(ns), **_axes_fills("points[0].transforms[0].translation", p),
                 **_axes_fills("points[0].transforms[0].rotation", q, "xyzw")}
        for arr, path in ((lv, "velocities[0].linear"), (av, "velocities[0].angular"),
                          (la, "accelerations[0].linear"), (aa, "accelerations[0].angular")):
            if arr is not None:
                fills.update(_axes_fills(f"points[0].{path}", arr))
        self._write_encoded(topic, MULTIDOF_TRAJECTORY, tmpl, fills, self._log(ns, log_time))
