"""Bag round trips checked against rosbags' reference (de)serialiser, and bad-bag errors."""
from __future__ import annotations

import numpy as np
import pytest

from cablelab import cdr
from cablelab.bags import (BagWriter, JOINT_STATE, bag_info, open_bag)
from cablelab.errors import CablelabError

AXIS_YAML = "plant: axis\nname: test axis\naxis:\n  joint_type: prismatic\n  inertia: 95.0\n"


def _ts():
    return cdr.typestore()


def _write_all(path, n=50, seed=0):
    rng = np.random.default_rng(seed)
    t = 100.0 + np.arange(n) * 1e-3 + rng.uniform(0, 1e-4, n)
    data = {
        "t": t,
        "js": rng.normal(size=(n, 3, 3)),
        "pos": rng.normal(size=(n, 3)),
        "quat": rng.normal(size=(n, 4)),
        "m": rng.uniform(300, 600, n),
        "com": rng.normal(size=(n, 3)),
        "arr": rng.normal(size=(n, 8)),
        "jt": rng.normal(size=(n, 3, 3)),
        "md": rng.normal(size=(n, 4, 3)),
    }
    with BagWriter(path) as w:
        w.write_description(AXIS_YAML)
        w.write_joint_states("/js", t, ["a", "bb", "ccc"], data["js"][:, 0], None, data["js"][:, 2],
                             log_time=t + 0.5)
        w.write_poses("/pose", t, data["pos"], data["quat"], frame_id="world")
        w.write_inertia("/inertia", t, data["m"], data["com"])
        w.write_float_arrays("/arr", t, data["arr"])
        w.write_joint_trajectory("/jt", t, ["slew", "luff", "hoist"], data["jt"][:, 0],
                                 data["jt"][:, 1], data["jt"][:, 2])
        w.write_multidof_trajectory("/md", t, data["pos"], data["quat"], data["md"][:, 0],
                                    data["md"][:, 1], None, None)
        w.write_clock(t)
        w.write_strings("/text", t[:3], ["x", "yy", "x"])
    return data


def test_round_trip_fast_codec_matches_rosbags_reference(tmp_path):
    bag_dir = tmp_path / "bag"
    d = _write_all(bag_dir)
    bag = open_bag(bag_dir)
    ts = _ts()
    # every written message deserialises with rosbags' reference to the values we wrote
    ref = [ts.deserialize_cdr(r, JOINT_STATE) for r in bag.raw("/js")[1]]
    assert [list(m.name) for m in ref[:1]] == [["a", "bb", "ccc"]]
    np.testing.assert_array_equal(np.array([m.position for m in ref]), d["js"][:, 0])
    assert all(len(m.velocity) == 0 for m in ref)
    stamps = np.array([m.header.stamp.sec + m.header.stamp.nanosec * 1e-9 for m in ref])
    np.testing.assert_allclose(stamps, d["t"], atol=1e-9)
    # and our fast reader gives the same
    js = bag.joint_state("/js")
    assert js.names == ["a", "bb", "ccc"]
    np.testing.assert_array_equal(js.position, d["js"][:, 0])
    np.testing.assert_array_equal(js.effort, d["js"][:, 2])
    assert np.isnan(js.velocity).all()
    np.testing.assert_allclose(js.t, d["t"], atol=1e-9)
    np.testing.assert_allclose(js.t_receive, d["t"] + 0.5, atol=1e-9)

    pose = bag.pose("/pose")
    np.testing.assert_array_equal(pose.position, d["pos"])
    np.testing.assert_array_equal(pose.quaternion, d["quat"])
    assert pose.frame_id == "world"
    ref_pose = ts.deserialize_cdr(bag.raw("/pose")[1][7], "geometry_msgs/msg/PoseStamped")
    assert ref_pose.pose.orientation.w == d["quat"][7, 3]

    ine = bag.inertia("/inertia")
    np.testing.assert_array_equal(ine.m, d["m"])
    np.testing.assert_array_equal(ine.com, d["com"])
    assert bag.inertia("/inertia").frame_id == "platform"

    arr = bag.float_array("/arr")
    np.testing.assert_array_equal(arr.data, d["arr"])
    np.testing.assert_allclose(arr.t, d["t"], atol=1e-9)

    jt = bag.joint_trajectory("/jt")
    assert jt.names == ["slew", "luff", "hoist"]
    for i, f in enumerate(("positions", "velocities", "accelerations")):
        np.testing.assert_array_equal(getattr(jt, f), d["jt"][:, i])
    ref_jt = ts.deserialize_cdr(bag.raw("/jt")[1][3], "trajectory_msgs/msg/JointTrajectory")
    np.testing.assert_array_equal(ref_jt.points[0].accelerations, d["jt"][3, 2])

    md = bag.multidof_trajectory("/md")
    np.testing.assert_array_equal(md.position, d["pos"])
    np.testing.assert_array_equal(md.quaternion, d["quat"])
    np.testing.assert_array_equal(md.linear_velocity, d["md"][:, 0])
    np.testing.assert_array_equal(md.angular_velocity, d["md"][:, 1])
    assert np.isnan(md.linear_acceleration).all()
    ref_md = ts.deserialize_cdr(bag.raw("/md")[1][5], "trajectory_msgs/msg/MultiDOFJointTrajectory")
    assert ref_md.points[0].velocities[0].angular.z == d["md"][5, 1, 2]
    assert list(ref_md.joint_names) == ["platform"]

    clock, log = bag.clock()
    np.testing.assert_allclose(clock, d["t"], atol=1e-9)
    assert bag.strings("/text") == ["x", "yy", "x"]
    assert bag.description.axis.inertia == 95.0
    assert bag.description_yaml == AXIS_YAML


def test_reader_decodes_messages_serialised_by_rosbags(tmp_path):
    """Messages built and serialised by the reference (varying names, empty fields, odd frame
    ids: several layouts in one topic) decode to the same numbers with the fast reader."""
    ts = _ts()
    T = ts.types
    rng = np.random.default_rng(1)
    msgs = []
    t = np.arange(40) * 0.01
    for i in range(40):
        names = ["j1", "j2"] if i % 3 else ["j2", "j1", "j3"]
        pos = rng.normal(size=len(names))
        vel = rng.normal(size=len(names)) if i % 2 else np.zeros(0)
        stamp = T["builtin_interfaces/msg/Time"](sec=int(t[i]), nanosec=int(round((t[i] % 1) * 1e9)))
        msgs.append(T[JOINT_STATE](header=T["std_msgs/msg/Header"](stamp=stamp, frame_id="f" * (i % 5)),
                                   name=names, position=pos, velocity=vel, effort=np.zeros(0)))
    with BagWriter(tmp_path / "b") as w:
        w.write_messages("/js", JOINT_STATE, t, msgs)
    js = open_bag(tmp_path / "b").joint_state("/js", names=["j1", "j2", "j3"])
    for i, m in enumerate(msgs):
        for col, name in enumerate(["j1", "j2", "j3"]):
            names = list(m.name)
            if name in names:
                assert js.position[i, col] == m.position[names.index(name)]
                want_v = m.velocity[names.index(name)] if len(m.velocity) else np.nan
                np.testing.assert_equal(js.velocity[i, col], want_v)
            else:
                assert np.isnan(js.position[i, col])
    np.testing.assert_allclose(js.t, t, atol=1e-9)
    assert np.isnan(js.effort).all()


def test_walk_matches_rosbags_sizes_for_every_contract_type():
    """The layout walker agrees with rosbags on where every message ends (all contract types)."""
    ts = _ts()
    for msgtype in ("sensor_msgs/msg/JointState", "geometry_msgs/msg/PoseStamped",
                    "geometry_msgs/msg/InertiaStamped", "std_msgs/msg/Float64MultiArray",
                    "trajectory_msgs/msg/JointTrajectory", "trajectory_msgs/msg/MultiDOFJointTrajectory",
                    "std_msgs/msg/String", "rosgraph_msgs/msg/Clock",
                    "diagnostic_msgs/msg/DiagnosticArray"):
        msg = _default(ts, msgtype)
        raw = bytes(ts.serialize_cdr(msg, msgtype))
        layout = cdr.walk(msgtype, raw)
        assert layout.size == len(raw)


def _default(ts, msgtype):
    """A message with every field at a default (sequences of structs with one element)."""
    cls = ts.types[msgtype]
    kwargs = {}
    for name, desc in ts.fielddefs[msgtype][1]:
        kind, arg = desc
        if kind == 1:
            kwargs[name] = "ab" if arg[0] == "string" else (False if arg[0] == "bool" else 0)
        elif kind == 2:
            kwargs[name] = _default(ts, arg)
        elif kind == 4:
            sub = arg[0]
            if sub[0] == 1 and sub[1][0] == "string":
                kwargs[name] = ["x", "yz"]
            elif sub[0] == 1:
                kwargs[name] = np.arange(3, dtype=np.float64 if "float" in sub[1][0] else np.uint8)
            else:
                kwargs[name] = [_default(ts, sub[1])]
        else:
            raise AssertionError(desc)
    return cls(**kwargs)


def test_info(tmp_path):
    _write_all(tmp_path / "bag", n=20)
    info = bag_info(tmp_path / "bag")
    counts = {t["name"]: t["count"] for t in info["topics"]}
    assert counts["/js"] == 20 and counts["/plant_description"] == 1 and counts["/text"] == 3
    assert info["plant"] == "axis"
    assert info["messages"] == sum(counts.values())
    # the .mcap file alone opens too
    assert bag_info(tmp_path / "bag" / "bag.mcap")["messages"] == info["messages"]


# ------------------------------------------------------------------------------------ bad input
def _one_line(exc) -> str:
    msg = str(exc.value)
    assert "\n" not in msg
    return msg


def test_missing_empty_truncated_and_non_bag_paths(tmp_path):
    with pytest.raises(CablelabError) as e:
        open_bag(tmp_path / "nope")
    assert "nope" in _one_line(e) and "not found" in _one_line(e)

    (tmp_path / "emptydir").mkdir()
    with pytest.raises(CablelabError) as e:
        open_bag(tmp_path / "emptydir")
    assert "emptydir" in _one_line(e) and "empty" in _one_line(e)

    (tmp_path / "empty.mcap").write_bytes(b"")
    with pytest.raises(CablelabError) as e:
        open_bag(tmp_path / "empty.mcap")
    assert "empty.mcap" in _one_line(e)

    (tmp_path / "text.mcap").write_text("hello, not a bag\n")
    with pytest.raises(CablelabError) as e:
        open_bag(tmp_path / "text.mcap")
    assert "text.mcap" in _one_line(e) and "not an MCAP" in _one_line(e)

    (tmp_path / "other").mkdir()
    (tmp_path / "other" / "notes.txt").write_text("x")
    with pytest.raises(CablelabError) as e:
        open_bag(tmp_path / "other")
    assert "not a rosbag2 bag" in _one_line(e)

    _write_all(tmp_path / "bag", n=2000)
    mcap = tmp_path / "bag" / "bag.mcap"
    data = mcap.read_bytes()
    mcap.write_bytes(data[: int(len(data) * 0.6)])
    with pytest.raises(CablelabError) as e:
        open_bag(tmp_path / "bag")
    assert "bag.mcap" in _one_line(e) and "truncated" in _one_line(e)
    # the complete part is still readable on request
    bag = open_bag(tmp_path / "bag", recover=True)
    total = sum(open_bag(tmp_path / "bag", recover=True).counts.values())
    assert bag.recovered and 0 < total < 7 * 2000 + 3
    js = bag.joint_state("/js")
    assert np.all(np.diff(js.t) > 0) and len(js.t) > 0

    # corrupt metadata.yaml
    _write_all(tmp_path / "bag2", n=5)
    (tmp_path / "bag2" / "metadata.yaml").write_text("::: not yaml [")
    with pytest.raises(CablelabError) as e:
        open_bag(tmp_path / "bag2")
    assert "bag2" in _one_line(e)


def test_require_names_topic_and_types(tmp_path):
    _write_all(tmp_path / "bag", n=3)
    bag = open_bag(tmp_path / "bag")
    with pytest.raises(CablelabError) as e:
        bag.joint_state("/cdpr/joint_states")
    assert "/cdpr/joint_states" in _one_line(e) and "not in bag" in _one_line(e)
    with pytest.raises(CablelabError) as e:
        bag.joint_state("/pose")
    msg = _one_line(e)
    assert "/pose" in msg and "geometry_msgs/msg/PoseStamped" in msg and JOINT_STATE in msg
    assert bag.has("/pose") and not bag.has("/nope")


def test_writer_refuses_existing_path_and_touches_nothing(tmp_path):
    _write_all(tmp_path / "bag", n=3)
    before = {p.name: p.read_bytes() for p in (tmp_path / "bag").iterdir()}
    with pytest.raises(CablelabError) as e:
        BagWriter(tmp_path / "bag")
    assert "bag" in _one_line(e) and "--overwrite" in _one_line(e)
    assert {p.name: p.read_bytes() for p in (tmp_path / "bag").iterdir()} == before
    # overwrite replaces a bag ...
    with BagWriter(tmp_path / "bag", overwrite=True) as w:
        w.write_clock([1.0, 2.0])
    assert open_bag(tmp_path / "bag").counts == {"/clock": 2}
    # ... but never a directory that is not a bag
    (tmp_path / "precious").mkdir()
    (tmp_path / "precious" / "thesis.tex").write_text("x")
    with pytest.raises(CablelabError):
        BagWriter(tmp_path / "precious", overwrite=True)
    assert (tmp_path / "precious" / "thesis.tex").read_text() == "x"


def test_writer_shape_errors_name_topic(tmp_path):
    with BagWriter(tmp_path / "b") as w:
        with pytest.raises(CablelabError) as e:
            w.write_joint_states("/js", [0.0, 1.0], ["a", "b"], position=np.zeros((2, 3)))
        assert "/js position" in _one_line(e)


def test_bag_readable_by_mcap_library(tmp_path):
    """Second implementation: the mcap package's indexed reader sees the same messages with ros2msg
    schemas (what Foxglove and the mcap CLI use)."""
    from mcap.reader import make_reader

    _write_all(tmp_path / "bag", n=30)
    with open(tmp_path / "bag" / "bag.mcap", "rb") as fh:
        reader = make_reader(fh)
        summary = reader.get_summary()
        encodings = {s.encoding for s in summary.schemas.values()}
        assert encodings == {"ros2msg"}
        assert {c.message_encoding for c in summary.channels.values()} == {"cdr"}
        counts = {}
        for _schema, channel, _msg in reader.iter_messages():
            counts[channel.topic] = counts.get(channel.topic, 0) + 1
    assert counts == open_bag(tmp_path / "bag").counts
    import yaml

    meta = yaml.safe_load((tmp_path / "bag" / "metadata.yaml").read_text())["rosbag2_bagfile_information"]
    assert meta["storage_identifier"] == "mcap"
    qos = {t["topic_metadata"]["name"]: t["topic_metadata"]["offered_qos_profiles"]
           for t in meta["topics_with_message_count"]}
    assert qos["/plant_description"][0]["durability"] == "transient_local"


def _write_mcap(path, topic, times, raws, **writer_options):
    """A ros2-profile MCAP of JointState messages written by the mcap package's own writer."""
    from mcap.writer import Writer as McapWriter

    msgdef, _ = _ts().generate_msgdef(JOINT_STATE, ros_version=2)
    with open(path, "wb") as fh:
        w = McapWriter(fh, **writer_options)
        w.start(profile="ros2", library="test")
        sid = w.register_schema(name=JOINT_STATE, encoding="ros2msg", data=msgdef.encode())
        cid = w.register_channel(topic=topic, message_encoding="cdr", schema_id=sid)
        for i, (stamp, raw) in enumerate(zip(times.tolist(), raws)):
            w.add_message(channel_id=cid, log_time=stamp, publish_time=stamp, data=raw, sequence=i)
        w.finish()


def _reference_messages(path):
    """(topic -> list of (log time, bytes)) read with rosbags' general reader (oracle)."""
    from rosbags.rosbag2 import Reader

    out = {}
    with Reader(path) as reader:
        for conn, stamp, data in reader.messages():
            out.setdefault(conn.topic, []).append((stamp, bytes(data)))
    return {k: sorted(v, key=lambda x: x[0]) for k, v in out.items()}


def test_fast_index_reader_matches_rosbags_reader(tmp_path):
    _write_all(tmp_path / "bag", n=700)
    bag = open_bag(tmp_path / "bag")
    ref = _reference_messages(tmp_path / "bag")
    assert set(ref) == set(bag.topics)
    for topic, msgs in ref.items():
        times, raws = bag.raw(topic)
        assert times.tolist() == [m[0] for m in msgs]
        assert raws == [m[1] for m in msgs]


def test_compressed_chunks_zstd_and_lz4_from_other_writers(tmp_path):
    """zstd chunks (rosbags writer) and lz4 chunks (the mcap package's writer) decode to the
    same messages through the fast index reader."""
    from mcap.writer import CompressionType
    from rosbags.rosbag2 import Writer
    from rosbags.rosbag2.enums import CompressionFormat, CompressionMode, StoragePlugin

    ts = _ts()
    t = np.arange(3000) * 1e-3
    pos = np.random.default_rng(2).normal(size=(3000, 2))
    with BagWriter(tmp_path / "plain") as w:
        w.write_joint_states("/js", t, ["a", "b"], pos)
    plain = open_bag(tmp_path / "plain")
    times, raws = plain.raw("/js")

    wz = Writer(tmp_path / "zstd", version=9, storage_plugin=StoragePlugin.MCAP)
    wz.set_compression(CompressionMode.STORAGE, CompressionFormat.ZSTD)
    with wz:
        conn = wz.add_connection("/js", JOINT_STATE, typestore=ts)
        for stamp, raw in zip(times.tolist(), raws):
            wz.write(conn, stamp, raw)

    (tmp_path / "lz4").mkdir()
    _write_mcap(tmp_path / "lz4" / "x.mcap", "/js", times, raws,
                compression=CompressionType.LZ4, chunk_size=20000)

    for path in (tmp_path / "zstd", tmp_path / "lz4" / "x.mcap"):
        bag = open_bag(path)
        got_t, got_raw = bag.raw("/js")
        assert got_t.tolist() == times.tolist() and got_raw == raws, path
        np.testing.assert_array_equal(bag.joint_state("/js").position, pos)


def test_info_verb_json_and_errors(tmp_path, capsys):
    import json

    from cablelab.cli import main

    _write_all(tmp_path / "bag", n=10)
    assert main(["info", str(tmp_path / "bag"), "--json"]) == 0
    out = capsys.readouterr()
    info = json.loads(out.out)
    assert info["plant"] == "axis" and {t["name"] for t in info["topics"]} >= {"/js", "/clock"}
    assert main(["info", str(tmp_path / "missing")]) == 2
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and "missing" in err and "Traceback" not in err


def test_unindexed_mcap_falls_back_to_general_reader(tmp_path):
    """An MCAP without chunks, indexes or statistics (valid per spec) is read by rosbags' reader
    with the same result."""
    from mcap.writer import CompressionType, IndexType

    from cablelab.mcap_index import read_index

    t = np.arange(300) * 1e-3
    with BagWriter(tmp_path / "p") as w:
        w.write_joint_states("/js", t, ["a"], np.arange(300.0)[:, None])
    times, raws = open_bag(tmp_path / "p").raw("/js")
    path = tmp_path / "flat.mcap"
    _write_mcap(path, "/js", times, raws, index_types=IndexType.NONE, use_summary_offsets=False,
                use_statistics=False, use_chunking=False, compression=CompressionType.NONE)
    assert read_index(path) is None
    bag = open_bag(path)
    np.testing.assert_array_equal(bag.joint_state("/js").position[:, 0], np.arange(300.0))
    assert bag.raw("/js")[1] == raws


def test_sqlite3_bag_is_read_too(tmp_path):
    """Older rosbag2 bags in sqlite3 storage go through rosbags' general reader."""
    from rosbags.rosbag2 import StoragePlugin, Writer

    t = np.arange(50) * 0.01
    with BagWriter(tmp_path / "p") as w:
        w.write_joint_states("/js", t, ["a"], np.arange(50.0)[:, None])
        w.write_description(AXIS_YAML)
    src = open_bag(tmp_path / "p")
    with Writer(tmp_path / "db", version=8, storage_plugin=StoragePlugin.SQLITE3) as w:
        for topic in ("/js", "/plant_description"):
            conn = w.add_connection(topic, src.topics[topic], typestore=_ts())
            for stamp, raw in zip(*[x.tolist() if hasattr(x, "tolist") else x for x in src.raw(topic)]):
                w.write(conn, stamp, raw)
    bag = open_bag(tmp_path / "db")
    np.testing.assert_array_equal(bag.joint_state("/js").position[:, 0], np.arange(50.0))
    assert bag.description.plant == "axis"


def test_contract_type_mismatch_is_named(tmp_path, capsys):
    from cablelab.cli import main

    t = np.arange(5) * 0.1
    with BagWriter(tmp_path / "b") as w:
        w.write_float_arrays("/cdpr/joint_states", t, np.zeros((5, 8)))  # wrong type
        w.write_joint_states("/cdpr/cable_tensions", t, ["cable_1"], effort=np.ones((5, 1)))
    bag = open_bag(tmp_path / "b")
    assert bag.contract_mismatches() == [("/cdpr/joint_states", "std_msgs/msg/Float64MultiArray",
                                          "sensor_msgs/msg/JointState")]
    with pytest.raises(CablelabError) as e:
        bag.check_contract()
    msg = _one_line(e)
    assert "/cdpr/joint_states" in msg and "Float64MultiArray" in msg and "JointState" in msg
    assert main(["info", str(tmp_path / "b")]) == 0
    assert "warning:  /cdpr/joint_states has type" in capsys.readouterr().out
