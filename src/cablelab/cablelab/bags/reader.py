"""Reading rosbag2 MCAP bags: :func:`open_bag` reads every message in one pass and decodes each
topic on demand with the vectorised CDR codec of :mod:`cablelab.cdr` into the series of
:mod:`cablelab.bags.series`; :func:`bag_info` summarises a bag."""
from __future__ import annotations

import os
import struct
from pathlib import Path

import numpy as np

from .. import cdr
from ..errors import CablelabError

from .series import (CLOCK, CLOCK_TOPIC, DESCRIPTION_TOPIC, FLOAT64_MULTI_ARRAY, INERTIA_STAMPED, JOINT_STATE, JOINT_TRAJECTORY,
                     MULTIDOF_TRAJECTORY, POSE_STAMPED, STRING, ArraySeries, InertiaSeries,
                     JointStateSeries, JointTrajectorySeries, MultiDofSeries, PoseSeries)


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


class Bag:
    """An opened bag: topic list, counts, time range and per-topic numpy readers.

    Attributes:
        path: the bag directory or file as given
        topics: topic name -> message type, e.g. ``'sensor_msgs/msg/JointState'``
        counts: topic name -> number of messages
        start, end: first and last log time, s
        recovered: True if the bag was unfinished (writer killed), damaged or incomplete and
            only its intact part was read (``--recover``)
        warnings: what was not read and why (one line each, with counts)
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
        #: integrity findings of the read (damaged chunks skipped, files of a split bag missing,
        #: message count against metadata.yaml): one line each
        self.warnings: list[str] = []
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
        from ..topics import COMMON, all_plant_topics

        contract = dict(COMMON)
        for table in all_plant_topics().values():
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
        """YAML text of the /plant_description messages, or None.

        Raises:
            CablelabError: two messages with different descriptions (naming both log times); a
                later re-publication of the same content is fine.
        """
        if self.topics.get(DESCRIPTION_TOPIC) != STRING or not self.counts[DESCRIPTION_TOPIC]:
            return None
        texts = self.strings(DESCRIPTION_TOPIC)
        first = texts[0]
        for i, text in enumerate(texts):
            if text != first and not _same_yaml(text, first):
                t = self._times[DESCRIPTION_TOPIC] * 1e-9
                raise CablelabError(
                    f"{self.path}: {DESCRIPTION_TOPIC}: two different descriptions in one bag (messages at "
                    f"{t[0]:.3f} s and {t[i]:.3f} s); give the right one with --description FILE")
        return texts[-1]

    @property
    def description(self):
        """The parsed /plant_description (:class:`~cablelab.description.Description`) or None.

        Raises:
            CablelabError: the message is not YAML, not a mapping of description keys, or an
                invalid description (naming the bag, the topic and the problem).
        """
        text = self.description_yaml
        if text is None:
            return None
        import yaml

        from ..description import load_description

        where = f"{self.path}: {DESCRIPTION_TOPIC}"
        try:
            data = yaml.safe_load(text)
        except yaml.YAMLError as exc:
            mark = getattr(exc, "problem_mark", None)
            line = f" (line {mark.line + 1})" if mark is not None else ""
            raise CablelabError(f"{where}: the message is not valid YAML{line}; give --description FILE") from None
        if not isinstance(data, dict):
            shown = " ".join(text.split())[:40]
            raise CablelabError(f"{where}: the message is not a YAML mapping of description keys "
                                f"(a {type(data).__name__}: {shown!r}); give --description FILE")
        try:   # a newline: always read as YAML text, never as a file name
            return load_description(text if "\n" in text else text + "\n")
        except CablelabError as exc:
            raise CablelabError(f"{where}: {exc}") from None

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


def _same_yaml(a: str, b: str) -> bool:
    """True if two description texts parse to the same data (a re-publication)."""
    import yaml

    try:
        return yaml.safe_load(a) == yaml.safe_load(b)
    except yaml.YAMLError:
        return False


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
    warnings: list[str] = []
    mcap_file = target if target.suffix == ".mcap" else None
    expected = None
    if mcap_file is None:
        meta = _check_metadata(target)
        listed, expected, per_file = _listed_files(meta)
        missing = [f for f in listed if not (target / f).is_file()]
        if missing:
            lost = sum(per_file.get(f) or 0 for f in missing)
            lost_text = f"{lost} messages" if all(per_file.get(f) is not None for f in missing) \
                else "an unknown number of messages"
            names = ", ".join(missing[:3]) + (", ..." if len(missing) > 3 else "")
            what = (f"split bag missing {len(missing)} of its {len(listed)} files listed in metadata.yaml "
                    f"({names}; {lost_text})")
            if not recover:
                raise _bag_error(given, f"{what}; read the files that are there with --recover")
            warnings.append(f"{given}: {what} not read")
            present = [target / f for f in listed if (target / f).is_file()]
            if not present:
                raise _bag_error(given, f"{what}; no file of the bag is left")
            return _merged(given, present, warnings, expected=expected and expected - lost)
        files = [target / f for f in listed] if listed else sorted(target.glob("*.mcap"))
        if len(files) == 1 and files[0].suffix == ".mcap":
            mcap_file = files[0]
        elif len(files) > 1 and all(f.suffix == ".mcap" for f in files):
            # a split bag: each file read and checked on its own (damaged chunks are named)
            return _merged(given, files, warnings, recover=recover, expected=expected)
        # sqlite3 (.db3) storage: rosbags' general reader
    if mcap_file is not None:
        return _open_mcap(given, mcap_file, recover, expected, warnings)

    try:
        topics, times, raws = _rosbags_file(target)
    except CablelabError:
        raise
    except Exception as exc:  # rosbags raises several error types for corrupt files
        mcaps = sorted(target.glob("*.mcap"))
        if mcaps:   # a damaged file of a split bag: read each file on its own
            return _merged(given, mcaps, warnings, recover=recover, expected=expected)
        text = str(exc).strip().splitlines()[0] if str(exc).strip() else type(exc).__name__
        raise _bag_error(given, f"unreadable bag ({text})") from None
    return _make_bag(given, topics, times, raws)


def _listed_files(meta: dict) -> tuple[list[str], int | None, dict[str, int | None]]:
    """(relative file paths, message count, {file: its message count}) of rosbag2 metadata."""
    info = meta.get("rosbag2_bagfile_information")
    info = info if isinstance(info, dict) else {}
    paths = info.get("relative_file_paths")
    listed = [f for f in (paths if isinstance(paths, list) else []) if isinstance(f, str)
              and f and not os.path.isabs(f) and ".." not in Path(f).parts]   # inside the bag only
    per_file = {}
    files = info.get("files")
    for f in files if isinstance(files, list) else []:
        if isinstance(f, dict) and isinstance(f.get("path"), str):
            n = f.get("message_count")
            per_file[f["path"]] = n if isinstance(n, int) and n >= 0 else None
    n = info.get("message_count")
    return listed, (n if isinstance(n, int) and n >= 0 else None), per_file


def _read_mcap(given, mcap_file: Path, recover: bool, expected=None):
    """(topics, times, raws or None, Bag or None, warnings, recovered) of one .mcap file: its
    fast index when intact, else rosbags, else (``recover``) the intact chunks."""
    from .salvage import salvage_mcap

    if not mcap_file.exists() or mcap_file.stat().st_size == 0:
        raise _bag_error(mcap_file, "empty MCAP file")
    with open(mcap_file, "rb") as fh:
        if fh.read(8) != b"\x89MCAP0\r\n":
            raise _bag_error(mcap_file, "not an MCAP file (bad magic bytes)")
    if _mcap_truncated(mcap_file):
        if not recover:
            raise _bag_error(mcap_file, "truncated MCAP file (writer killed before closing?); "
                                        "read its complete part with --recover")
        s = salvage_mcap(mcap_file, expected)
        warn = [f"{given}: {s.describe()}"] if s.damaged else []
        return s.topics, s.times, s.raws, warn, True
    from ..mcap_index import read_index

    try:
        index = read_index(mcap_file)
    except (struct.error, ValueError, IndexError, OSError):
        index = None
    if index is not None:
        return index, None, None, [], False
    s = salvage_mcap(mcap_file, expected)   # no usable index: is the file damaged?
    if s.damaged:
        if not recover:
            lost = "an unknown number of" if s.lost is None else s.lost
            raise _bag_error(given, f"damaged MCAP file: {s.damaged} of {s.chunks} chunks do not decode "
                                    f"({lost} messages); read the intact chunks with --recover (or "
                                    f"rewrite them with cablelab repair)")
        return s.topics, s.times, s.raws, [f"{given}: {s.describe()}"], True
    try:
        topics, times, raws = _rosbags_file(mcap_file)
    except Exception as exc:  # noqa: BLE001 - rosbags raises several error types for corrupt files
        first = str(exc).strip().splitlines()[0] if str(exc).strip() else type(exc).__name__
        raise _bag_error(given, f"unreadable bag ({first})") from None
    return topics, times, raws, [], False


def _rosbags_file(path: Path):
    """(topics, times, raws) of a bag directory or one .mcap file through rosbags' general reader."""
    from rosbags.rosbag2 import Reader

    with Reader(path) as reader:
        conns = reader.connections
        topics = {c.topic: c.msgtype for c in conns}
        times = {c.topic: [] for c in conns}
        raws = {c.topic: [] for c in conns}
        for conn, stamp, data in reader.messages():
            times[conn.topic].append(stamp)
            raws[conn.topic].append(bytes(data))
    return topics, times, raws


def _open_mcap(given, mcap_file: Path, recover: bool, expected, warnings: list[str]) -> "Bag":
    got, times, raws, warn, recovered = _read_mcap(given, mcap_file, recover, expected)
    if times is None:   # the fast index
        ti = got.topics
        bag = Bag(given, {k: v.msgtype for k, v in ti.items()}, {k: v.log_time for k, v in ti.items()},
                  got.buffer, {k: v.offset for k, v in ti.items()}, {k: v.length for k, v in ti.items()})
    else:
        bag = _make_bag(given, got, times, raws, recovered=recovered)
    bag.warnings = warnings + warn
    _check_count(bag, expected)
    return bag


def _merged(given, files: list[Path], warnings: list[str], *, recover: bool = True, expected=None) -> "Bag":
    """One Bag of several .mcap files (a split bag read file by file)."""
    topics, times, raws, recovered = {}, {}, {}, False
    for f in files:
        got, t, r, warn, rec = _read_mcap(given, f, recover)
        if t is None:   # an Index: back to per-message lists
            t = {k: v.log_time.tolist() for k, v in got.topics.items()}
            buf = got.buffer
            r = {k: [bytes(buf[o:o + n]) for o, n in zip(v.offset.tolist(), v.length.tolist())]
                 for k, v in got.topics.items()}
            got = {k: v.msgtype for k, v in got.topics.items()}
        for k, v in got.items():
            topics.setdefault(k, v)
            times.setdefault(k, []).extend(t.get(k, []))
            raws.setdefault(k, []).extend(r.get(k, []))
        warnings = warnings + warn
        recovered = recovered or rec
    bag = _make_bag(given, topics, times, raws, recovered=recovered or bool(warnings))
    bag.warnings = warnings
    _check_count(bag, expected)
    return bag


def _check_count(bag: "Bag", expected) -> None:
    """A bag holding another number of messages than its metadata.yaml lists: a warning."""
    n = int(sum(bag.counts.values()))
    if expected is not None and n != expected and not bag.warnings:
        bag.warnings.append(f"{bag.path}: metadata.yaml lists {expected} messages, the bag holds {n}")


def _check_metadata(bag_dir: Path) -> dict:
    """metadata.yaml must be a rosbag2 bag description (one-line error otherwise)."""
    import yaml

    meta = bag_dir / "metadata.yaml"
    try:
        data = yaml.safe_load(meta.read_text(encoding="utf-8"))
    except (OSError, UnicodeError, yaml.YAMLError) as exc:
        raise _bag_error(meta, f"unreadable metadata ({type(exc).__name__})") from None
    if not isinstance(data, dict) or "rosbag2_bagfile_information" not in data:
        raise _bag_error(meta, "not rosbag2 metadata (no rosbag2_bagfile_information)")
    return data


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
    try:
        text = bag.description_yaml
    except CablelabError as exc:   # disagreeing descriptions: say so, show the rest
        text = None
        bag.warnings.append(str(exc))
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
    if bag.warnings:
        info["warnings"] = list(bag.warnings)
    info["contract_mismatches"] = [{"topic": t, "type": have, "contract_type": want}
                                   for t, have, want in bag.contract_mismatches()]
    lost = recorder_lost(path)
    if lost is not None:
        info["lost"] = lost
    return info


LOST_KEY = "cablelab.lost."   # metadata.yaml custom_data: samples the recorder lost, per topic


def recorder_lost(path) -> dict[str, int] | None:
    """Samples ``cablelab record`` counted as lost, per topic, from metadata.yaml's
    ``custom_data`` (``cablelab.lost.<topic>: <count>``); None when the bag has no such record
    (not written by ``cablelab record``, or the recorder was killed before closing it)."""
    import yaml

    path = Path(path)
    meta = (path if path.is_dir() else path.parent) / "metadata.yaml"
    try:
        data = yaml.safe_load(meta.read_text(encoding="utf-8"))
        custom = data["rosbag2_bagfile_information"].get("custom_data") or {}
    except (OSError, UnicodeError, yaml.YAMLError, KeyError, TypeError, AttributeError):
        return None
    lost = {}
    for key, value in custom.items():
        if str(key).startswith(LOST_KEY):
            try:
                lost[str(key)[len(LOST_KEY):]] = int(value)
            except (TypeError, ValueError):
                continue
    return lost if lost else None


