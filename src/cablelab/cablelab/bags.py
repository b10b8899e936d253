"""rosbag2 MCAP bags: read contract topics into numpy arrays, write them from numpy arrays.

A bag is a rosbag2 directory (``metadata.yaml`` + ``<name>.mcap``, ROS 2 Jazzy typestore, CDR
messages with ``ros2msg`` schemas) as written by ``ros2 bag record -s mcap``; it opens in
``ros2 bag info``, Foxglove and the mcap tools. A bare ``.mcap`` file is accepted too.

Reading: :func:`open_bag` reads every message of the bag in one pass (rosbags' MCAP reader) and
decodes each topic on demand with the vectorised CDR codec of :mod:`cablelab.cdr` into small
dataclasses of numpy arrays (:class:`JointStateSeries`, :class:`PoseSeries`, ...). Times are in
seconds: ``t`` is the header stamp (sim time when /clock is published), ``t_receive`` the bag's
log time.

Writing: :class:`BagWriter` writes whole time series per call (``write_joint_states(topic, t,
names, position, ...)``), vectorised the same way, plus ``write_raw`` for already-serialised
messages (the recorder).

Every problem with the user's input raises :class:`~cablelab.errors.CablelabError` with one line
naming the path, topic or types.
"""
from __future__ import annotations

import os
import shutil
import struct
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from . import cdr
from .errors import CablelabError

# ---------------------------------------------------------------------------------------- types
JOINT_STATE = "sensor_msgs/msg/JointState"
POSE_STAMPED = "geometry_msgs/msg/PoseStamped"
INERTIA_STAMPED = "geometry_msgs/msg/InertiaStamped"
FLOAT64_MULTI_ARRAY = "std_msgs/msg/Float64MultiArray"
JOINT_TRAJECTORY = "trajectory_msgs/msg/JointTrajectory"
MULTIDOF_TRAJECTORY = "trajectory_msgs/msg/MultiDOFJointTrajectory"
STRING = "std_msgs/msg/String"
CLOCK = "rosgraph_msgs/msg/Clock"

DESCRIPTION_TOPIC = "/plant_description"
CLOCK_TOPIC = "/clock"


# ---------------------------------------------------------------------------------------- series
@dataclass
class JointStateSeries:
    """sensor_msgs/JointState over time. Arrays (N, k) in the column order of ``names``; NaN
    where a message left the field empty or did not contain that joint."""

    t: np.ndarray
    names: list[str]
    position: np.ndarray
    velocity: np.ndarray
    effort: np.ndarray
    t_receive: np.ndarray

    def column(self, name: str) -> int:
        """Index of a joint in the arrays (CablelabError naming the joint if absent)."""
        try:
            return self.names.index(name)
        except ValueError:
            raise CablelabError(f"joint {name!r} not in {self.names}") from None


@dataclass
class PoseSeries:
    """geometry_msgs/PoseStamped over time: position (N, 3) m, quaternion (N, 4) as x, y, z, w."""

    t: np.ndarray
    position: np.ndarray
    quaternion: np.ndarray
    frame_id: str = ""
    t_receive: np.ndarray | None = None


@dataclass
class InertiaSeries:
    """geometry_msgs/InertiaStamped over time: mass m (N,) kg, centre of mass com (N, 3) m."""

    t: np.ndarray
    m: np.ndarray
    com: np.ndarray
    frame_id: str = ""
    t_receive: np.ndarray | None = None


@dataclass
class ArraySeries:
    """std_msgs/Float64MultiArray over time. ``t`` is the log time (the message has no header);
    ``data`` (N, k), NaN-padded if lengths differ."""

    t: np.ndarray
    data: np.ndarray
    t_receive: np.ndarray | None = None


@dataclass
class JointTrajectorySeries:
    """trajectory_msgs/JointTrajectory, first point of each message: (N, k), NaN if empty."""

    t: np.ndarray
    names: list[str]
    positions: np.ndarray
    velocities: np.ndarray
    accelerations: np.ndarray
    t_receive: np.ndarray | None = None


@dataclass
class MultiDofSeries:
    """trajectory_msgs/MultiDOFJointTrajectory, first point and first joint of each message.
    position (N, 3) m, quaternion (N, 4) x, y, z, w, velocities and accelerations (N, 3), NaN if
    empty."""

    t: np.ndarray
    position: np.ndarray
    quaternion: np.ndarray
    linear_velocity: np.ndarray
    angular_velocity: np.ndarray
    linear_acceleration: np.ndarray
    angular_acceleration: np.ndarray
    t_receive: np.ndarray | None = None


# ---------------------------------------------------------------------------------------- reading
def _bag_error(path, msg: str) -> CablelabError:
    return CablelabError(f"{path}: {msg}")


def _locate(path: Path) -> Path:
    """Check a bag path and return what rosbags should open (directory or .mcap file)."""
    if not path.exists():
        raise _bag_error(path, "no such bag (file or directory not found)")
    if path.is_dir():
        mcaps = sorted(path.glob("*.mcap"))
        if not (path / "metadata.yaml").exists():
            if not any(path.iterdir()):
                raise _bag_error(path, "empty directory, not a rosbag2 bag")
            if len(mcaps) == 1:
                return mcaps[0]  # metadata.yaml missing (recorder killed?): read the .mcap itself
            raise _bag_error(path, "not a rosbag2 bag (no metadata.yaml and no single .mcap file)")
        return path
    if path.stat().st_size == 0:
        raise _bag_error(path, "empty file, not an MCAP bag")
    with open(path, "rb") as fh:
        magic = fh.read(8)
    if magic != b"\x89MCAP0\r\n":
        raise _bag_error(path, "not an MCAP file (bad magic bytes)")
    return path


def _mcap_truncated(path: Path) -> bool:
    """True if an .mcap file lacks the closing magic (writer killed before closing)."""
    with open(path, "rb") as fh:
        fh.seek(0, os.SEEK_END)
        if fh.tell() < 16:
            return True
        fh.seek(-8, os.SEEK_END)
        return fh.read(8) != b"\x89MCAP0\r\n"


def _read_stream(path: Path) -> tuple[dict[str, str], dict[str, list], dict[str, list]]:
    """Read the complete records of an unfinished .mcap file (no footer, no index)."""
    from mcap.records import Channel, Message, Schema
    from mcap.stream_reader import StreamReader

    topics: dict[str, str] = {}
    times: dict[str, list] = {}
    raws: dict[str, list] = {}
    channels: dict[int, tuple[str, str]] = {}
    schemas: dict[int, str] = {}
    with open(path, "rb") as fh:
        reader = StreamReader(fh, skip_magic=False, emit_chunks=False)
        try:
            for rec in reader.records:
                if isinstance(rec, Schema):
                    schemas[rec.id] = rec.name
                elif isinstance(rec, Channel):
                    channels[rec.id] = (rec.topic, schemas.get(rec.schema_id, ""))
                    topics[rec.topic] = channels[rec.id][1]
                    times.setdefault(rec.topic, [])
                    raws.setdefault(rec.topic, [])
                elif isinstance(rec, Message) and rec.channel_id in channels:
                    topic = channels[rec.channel_id][0]
                    times[topic].append(rec.log_time)
                    raws[topic].append(bytes(rec.data))
        except Exception:  # noqa: BLE001 - the truncated tail: keep what was complete
            pass
    return topics, times, raws


class Bag:
    """An opened bag: topic list, counts, time range and per-topic numpy readers.

    Attributes:
        path: the bag directory or file as given
        topics: topic name -> message type, e.g. ``'sensor_msgs/msg/JointState'``
        counts: topic name -> number of messages
        start, end: first and last log time, s
        recovered: True if the bag was unfinished (writer killed) and read up to its last
            complete record
    """

    def __init__(self, path, topics: dict[str, str], times: dict[str, np.ndarray], buffer,
                 offsets: dict[str, np.ndarray], lengths: dict[str, np.ndarray],
                 recovered: bool = False):
        self.path = str(path)
        self.topics = dict(topics)
        self._times = times
        self._buffer = memoryview(buffer)
        self._offsets = offsets
        self._lengths = lengths
        self._raws: dict[str, list[bytes]] = {}
        self.counts = {name: int(len(times.get(name, ()))) for name in topics}
        all_t = [a for a in times.values() if len(a)]
        self.start = float(min(a[0] for a in all_t)) * 1e-9 if all_t else 0.0
        self.end = float(max(a[-1] for a in all_t)) * 1e-9 if all_t else 0.0
        self.recovered = recovered
        self._cache: dict[object, object] = {}

    def __repr__(self) -> str:
        return f"Bag({self.path!r}, {len(self.topics)} topics, {sum(self.counts.values())} messages)"

    # ---- topics
    def has(self, topic: str) -> bool:
        """True if the bag holds ``topic`` (with any type and at least its connection)."""
        return topic in self.topics

    def require(self, topic: str, msgtype: str) -> None:
        """Raise CablelabError naming the topic if absent, or both types if it has another type."""
        if topic not in self.topics:
            have = ", ".join(sorted(self.topics)) or "none"
            raise CablelabError(f"{self.path}: topic {topic} not in bag (topics: {have})")
        if self.topics[topic] != msgtype:
            raise CablelabError(f"{self.path}: topic {topic} has type {self.topics[topic]}, "
                                f"expected {msgtype}")

    def contract_mismatches(self) -> list[tuple[str, str, str]]:
        """(topic, type in the bag, contract type) of every contract topic (CONTRACT section 2,
        :mod:`cablelab.topics`) recorded with another type."""
        from .topics import COMMON, PLANT_TOPICS

        contract = dict(COMMON)
        for table in PLANT_TOPICS.values():
            contract.update(table)
        return [(t, have, contract[t]) for t, have in sorted(self.topics.items())
                if t in contract and have != contract[t]]

    def check_contract(self) -> None:
        """CablelabError naming the first contract topic recorded with another type (both types)."""
        bad = self.contract_mismatches()
        if bad:
            topic, have, want = bad[0]
            more = f" (and {len(bad) - 1} more)" if len(bad) > 1 else ""
            raise CablelabError(f"{self.path}: topic {topic} has type {have}, the contract says "
                                f"{want}{more}")

    def raw(self, topic: str) -> tuple[np.ndarray, list[bytes]]:
        """(log times in ns (N,), serialised CDR messages) of a topic, sorted by log time."""
        if topic not in self.topics:
            self.require(topic, "")
        if topic not in self._raws:
            buf = self._buffer
            self._raws[topic] = [bytes(buf[o:o + n]) for o, n in
                                 zip(self._offsets[topic].tolist(), self._lengths[topic].tolist())]
        return self._times[topic], self._raws[topic]

    def messages(self, topic: str) -> list:
        """rosbags message objects of a topic (slow, general; for tools and tests)."""
        ts = cdr.typestore()
        _, raws = self.raw(topic)
        return [ts.deserialize_cdr(r, self.topics[topic]) for r in raws]

    def clear_cache(self) -> None:
        """Forget the decoded topics (the next read decodes again; for benchmarks)."""
        self._cache.clear()

    def _groups(self, topic: str, msgtype: str):
        self.require(topic, msgtype)
        key = (topic, msgtype)
        if key not in self._cache:
            self._cache[key] = cdr.decode_buffer(msgtype, self._buffer, self._offsets[topic],
                                                 self._lengths[topic], topic=topic)
        return self._cache[key]

    def _log_s(self, topic: str) -> np.ndarray:
        return self._times[topic] * 1e-9

    # ---- description
    @property
    def description_yaml(self) -> str | None:
        """YAML text of the last /plant_description message, or None."""
        if self.topics.get(DESCRIPTION_TOPIC) != STRING or not self.counts[DESCRIPTION_TOPIC]:
            return None
        return self.strings(DESCRIPTION_TOPIC)[-1]

    @property
    def description(self):
        """The parsed /plant_description (:class:`~cablelab.description.Description`) or None."""
        text = self.description_yaml
        if text is None:
            return None
        from .description import load_description

        try:
            return load_description(text)
        except CablelabError as exc:
            raise CablelabError(f"{self.path}: {DESCRIPTION_TOPIC}: {exc}") from None

    # ---- typed readers
    def joint_state(self, topic: str, names: list[str] | None = None) -> JointStateSeries:
        """Read a sensor_msgs/JointState topic.

        Args:
            names: joint columns to return (default: the names of the first message). A joint a
                message lacks gives NaN in that row.
        """
        t, names, out = _named_columns(self._groups(topic, JOINT_STATE), self.counts[topic], names,
                                       "name", ("position", "velocity", "effort"))
        return JointStateSeries(t=t, names=names, t_receive=self._log_s(topic), **out)

    def pose(self, topic: str) -> PoseSeries:
        """Read a geometry_msgs/PoseStamped topic."""
        groups = self._groups(topic, POSE_STAMPED)
        n = self.counts[topic]
        t = _stamps(groups, n)
        pos = np.full((n, 3), np.nan)
        quat = np.full((n, 4), np.nan)
        for g in groups:
            pos[g.rows] = _stack(g, "pose.position.", "xyz")
            quat[g.rows] = _stack(g, "pose.orientation.", "xyzw")
        return PoseSeries(t=t, position=pos, quaternion=quat, frame_id=_frame_id(groups),
                          t_receive=self._log_s(topic))

    def inertia(self, topic: str) -> InertiaSeries:
        """Read a geometry_msgs/InertiaStamped topic (mass and centre of mass)."""
        groups = self._groups(topic, INERTIA_STAMPED)
        n = self.counts[topic]
        t = _stamps(groups, n)
        m = np.full(n, np.nan)
        com = np.full((n, 3), np.nan)
        for g in groups:
            m[g.rows] = g.get("inertia.m")[:, 0]
            com[g.rows] = _stack(g, "inertia.com.", "xyz")
        return InertiaSeries(t=t, m=m, com=com, frame_id=_frame_id(groups),
                             t_receive=self._log_s(topic))

    def float_array(self, topic: str) -> ArraySeries:
        """Read a std_msgs/Float64MultiArray topic (``t`` = log time)."""
        groups = self._groups(topic, FLOAT64_MULTI_ARRAY)
        n = self.counts[topic]
        k = max((g.layout.seqlen.get("data", 0) for g in groups), default=0)
        data = np.full((n, k), np.nan)
        for g in groups:
            v = g.get("data")
            if v is not None:
                data[g.rows, :v.shape[1]] = v
        t = self._log_s(topic)
        return ArraySeries(t=t, data=data, t_receive=t)

    def joint_trajectory(self, topic: str, names: list[str] | None = None) -> JointTrajectorySeries:
        """Read a trajectory_msgs/JointTrajectory topic: the first point of each message."""
        t, names, out = _named_columns(self._groups(topic, JOINT_TRAJECTORY), self.counts[topic], names,
                                       "joint_names", ("positions", "velocities", "accelerations"),
                                       prefix="points[0].")
        return JointTrajectorySeries(t=t, names=names, t_receive=self._log_s(topic), **out)

    def multidof_trajectory(self, topic: str) -> MultiDofSeries:
        """Read a trajectory_msgs/MultiDOFJointTrajectory topic: first point, first joint."""
        groups = self._groups(topic, MULTIDOF_TRAJECTORY)
        n = self.counts[topic]
        t = _stamps(groups, n)
        fields = {
            "position": ("points[0].transforms[0].translation.", "xyz"),
            "quaternion": ("points[0].transforms[0].rotation.", "xyzw"),
            "linear_velocity": ("points[0].velocities[0].linear.", "xyz"),
            "angular_velocity": ("points[0].velocities[0].angular.", "xyz"),
            "linear_acceleration": ("points[0].accelerations[0].linear.", "xyz"),
            "angular_acceleration": ("points[0].accelerations[0].angular.", "xyz"),
        }
        out = {f: np.full((n, len(axes)), np.nan) for f, (_, axes) in fields.items()}
        for g in groups:
            for f, (prefix, axes) in fields.items():
                if prefix + axes[0] in g.layout.spans:
                    out[f][g.rows] = _stack(g, prefix, axes)
        return MultiDofSeries(t=t, t_receive=self._log_s(topic), **out)

    def strings(self, topic: str) -> list[str]:
        """Read a std_msgs/String topic: the texts in log-time order."""
        groups = self._groups(topic, STRING)
        out = [""] * self.counts[topic]
        for g in groups:  # one group = identical bytes = identical text
            text = g.layout.strings.get("data", "")
            for r in g.rows.tolist():
                out[r] = text
        return out

    def clock(self, topic: str = CLOCK_TOPIC) -> tuple[np.ndarray, np.ndarray]:
        """(clock time s (N,), log time s (N,)) of a rosgraph_msgs/Clock topic."""
        return _stamps(self._groups(topic, CLOCK), self.counts[topic], "clock"), self._log_s(topic)


def _names(layout: cdr.Layout, path: str) -> list[str]:
    return [layout.strings[f"{path}[{i}]"] for i in range(layout.seqlen.get(path, 0))]


def _column_map(have: list[str], want: list[str]) -> tuple[np.ndarray, np.ndarray]:
    """(source columns in ``have``, destination columns in ``want``) of the common names."""
    pos = {name: i for i, name in enumerate(have)}
    pairs = [(pos[name], j) for j, name in enumerate(want) if name in pos]
    if not pairs:
        return np.zeros(0, dtype=int), np.zeros(0, dtype=int)
    src, dst = np.array(pairs).T
    return src, dst


def _stack(g: cdr.Group, prefix: str, axes: str) -> np.ndarray:
    return np.hstack([g.get(prefix + a) for a in axes])


def _stamps(groups, n: int, path: str = "header.stamp") -> np.ndarray:
    """(n,) time in s of a builtin_interfaces/Time field of every message of a topic."""
    t = np.full(n, np.nan)
    for g in groups:
        t[g.rows] = g.stamp(path)
    return t


def _frame_id(groups) -> str:
    """header.frame_id of the first message ("" for an empty topic)."""
    return groups[0].layout.strings.get("header.frame_id", "") if groups else ""


def _named_columns(groups, n: int, names, name_field: str, fields, prefix: str = ""):
    """``(t (n,), names, {field: (n, k)})`` of a message type with a joint-name list
    (JointState ``name``, JointTrajectory ``joint_names``): columns follow ``names`` (default
    the first message's); a joint a message lacks gives NaN in its row."""
    if names is None:
        names = _names(groups[0].layout, name_field) if groups else []
    names = list(names)
    t = _stamps(groups, n)
    out = {f: np.full((n, len(names)), np.nan) for f in fields}
    for g in groups:
        src, dst = _column_map(_names(g.layout, name_field), names)
        for f, arr in out.items():
            v = g.get(prefix + f)
            if v is None:
                continue
            valid = src < v.shape[1]
            arr[np.ix_(g.rows, dst[valid])] = v[:, src[valid]]
    return t, names, out


def open_bag(path, *, recover: bool = False) -> Bag:
    """Open a rosbag2 MCAP bag (directory or .mcap file) and read all its messages.

    Args:
        path: bag directory or .mcap file
        recover: read an unfinished bag (writer killed: no MCAP footer / no metadata.yaml) up to
            its last complete record instead of refusing it

    Raises:
        CablelabError: missing, empty, truncated or non-bag path (one line naming the path).
    """
    given = Path(path)
    target = _locate(given)
    mcap_file = target if target.suffix == ".mcap" else None
    if mcap_file is None:
        files = sorted(target.glob("*.mcap"))
        if len(files) == 1:
            mcap_file = files[0]
        # several .mcap files (split bag) or sqlite3 (.db3) storage: rosbags' general reader
    if mcap_file is not None and (not mcap_file.exists() or mcap_file.stat().st_size == 0):
        raise _bag_error(mcap_file, "empty MCAP file")
    if mcap_file is not None and _mcap_truncated(mcap_file):
        if not recover:
            raise _bag_error(mcap_file, "truncated MCAP file (writer killed before closing?); "
                                        "read its complete part with --recover")
        topics, times, raws = _read_stream(mcap_file)
        return _make_bag(given, topics, times, raws, recovered=True)
    if target.is_dir():
        _check_metadata(target)
    if mcap_file is not None:
        from .mcap_index import read_index

        try:
            index = read_index(mcap_file)
        except (struct.error, ValueError, IndexError, OSError):
            index = None
        if index is not None:
            ti = index.topics
            return Bag(given, {k: v.msgtype for k, v in ti.items()},
                       {k: v.log_time for k, v in ti.items()}, index.buffer,
                       {k: v.offset for k, v in ti.items()}, {k: v.length for k, v in ti.items()})

    from rosbags.rosbag2 import Reader

    try:
        with Reader(target) as reader:
            conns = reader.connections
            topics = {c.topic: c.msgtype for c in conns}
            times = {c.topic: [] for c in conns}
            raws = {c.topic: [] for c in conns}
            for conn, stamp, data in reader.messages():
                times[conn.topic].append(stamp)
                raws[conn.topic].append(bytes(data))
    except CablelabError:
        raise
    except Exception as exc:  # rosbags raises several error types for corrupt files
        text = str(exc).strip().splitlines()[0] if str(exc).strip() else type(exc).__name__
        raise _bag_error(given, f"unreadable bag ({text})") from None
    return _make_bag(given, topics, times, raws)


def _check_metadata(bag_dir: Path) -> None:
    """metadata.yaml must be a rosbag2 bag description (one-line error otherwise)."""
    import yaml

    meta = bag_dir / "metadata.yaml"
    try:
        data = yaml.safe_load(meta.read_text(encoding="utf-8"))
    except (OSError, UnicodeError, yaml.YAMLError) as exc:
        raise _bag_error(meta, f"unreadable metadata ({type(exc).__name__})") from None
    if not isinstance(data, dict) or "rosbag2_bagfile_information" not in data:
        raise _bag_error(meta, "not rosbag2 metadata (no rosbag2_bagfile_information)")


def _make_bag(path, topics, times, raws, recovered: bool = False) -> Bag:
    """A Bag from per-topic lists of log times and serialised messages."""
    tarr, offsets, lengths, chunks = {}, {}, {}, []
    pos = 0
    for name in topics:
        t = np.asarray(times.get(name, []), dtype=np.int64)
        order = np.argsort(t, kind="stable")
        msgs = [raws[name][i] for i in order] if len(order) else []
        n = np.fromiter((len(m) for m in msgs), dtype=np.int64, count=len(msgs))
        offsets[name] = pos + np.concatenate([[0], np.cumsum(n)[:-1]]).astype(np.int64) if len(n) else n
        lengths[name] = n
        tarr[name] = t[order]
        chunks.extend(msgs)
        pos += int(n.sum())
    return Bag(path, topics, tarr, b"".join(chunks), offsets, lengths, recovered=recovered)


def bag_info(path, *, recover: bool = False) -> dict:
    """Summary of a bag: ``{"path", "duration", "messages", "topics": [{"name", "type",
    "count"}], "plant"}`` (plant = the description's plant id or None)."""
    bag = open_bag(path, recover=recover)
    plant = None
    text = bag.description_yaml
    if text is not None:
        import yaml

        try:
            data = yaml.safe_load(text)
            plant = data.get("plant") if isinstance(data, dict) else None
        except yaml.YAMLError:
            plant = None
    info = {
        "path": bag.path,
        "duration": bag.end - bag.start,
        "messages": int(sum(bag.counts.values())),
        "topics": [{"name": n, "type": t, "count": bag.counts[n]} for n, t in sorted(bag.topics.items())],
        "plant": plant,
    }
    if bag.recovered:
        info["recovered"] = True
    info["contract_mismatches"] = [{"topic": t, "type": have, "contract_type": want}
                                   for t, have, want in bag.contract_mismatches()]
    return info


# ---------------------------------------------------------------------------------------- writing
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
        overwrite: replace an existing bag directory; without it an existing path is an error and
            nothing is touched. A path that exists but is not a bag is never replaced.
    """

    def __init__(self, path, overwrite: bool = False):
        self.path = Path(path)
        if self.path.suffix == ".mcap":
            raise _bag_error(self.path, "give a bag directory name, not a .mcap file name")
        if self.path.exists():
            if not overwrite:
                raise _bag_error(self.path, "exists already (use --overwrite to replace it)")
            if not _looks_like_bag(self.path):
                raise _bag_error(self.path, "exists and is not a bag; not overwriting it")
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
        self._writer = Writer(self.path, version=9, storage_plugin=StoragePlugin.MCAP)
        self._writer.open()
        return self

    def close(self) -> None:
        if self._writer is not None:
            self._writer.close()
            self._writer = None

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


def _looks_like_bag(path: Path) -> bool:
    if path.is_dir():
        entries = list(path.iterdir())
        return not entries or (path / "metadata.yaml").exists() or any(
            e.suffix == ".mcap" for e in entries)
    return path.suffix == ".mcap"
