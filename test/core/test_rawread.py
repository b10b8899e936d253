"""Incoming serialised messages decoded without rclpy objects (cablelab.ros.rawmsg.RawReader)
agree with rclpy's own deserialisation (the oracle), follow layout changes and refuse garbage."""
import numpy as np
import pytest
from hypothesis import given, settings, strategies as st

rclpy = pytest.importorskip("rclpy")


def _same(a, b):
    if a is None or b is None:
        return a is None and b is None
    return np.array_equal(np.asarray(a), np.asarray(b))


def test_joint_state_bytes_equal_rclpy_decoding():
    from rclpy.serialization import serialize_message
    from sensor_msgs.msg import JointState

    from cablelab.ros import convert, rawmsg

    reader = rawmsg.RawReader(JointState)
    rng = np.random.default_rng(1)
    cases = []
    for n, fields in ((8, "pve"), (8, "pve"), (8, "pe"), (3, "v"), (0, ""), (8, "pve")):
        vals = {f: rng.normal(size=n) if f[0] in fields else None for f in ("position", "velocity", "effort")}
        msg = convert.joint_state_msg(rng.uniform(0, 1e5), [f"j{i}" for i in range(n)], **vals)
        cases.append(msg)
    for msg in cases:
        want = convert.joint_state_arrays(msg)
        got = rawmsg.joint_state_arrays(serialize_message(msg), reader)
        assert got[0] == pytest.approx(want[0], abs=1e-9) and got[1] == want[1]
        assert all(_same(g, w) for g, w in zip(got[2:], want[2:]))
    # a layout is parsed once per change of structure, not per sample
    assert reader.parsed == 5
    # a message object goes through rclpy's path unchanged
    assert rawmsg.joint_state_arrays(cases[0], reader)[1] == [f"j{i}" for i in range(8)]
    # a layout change that keeps the size (names of the same length, one field moved to
    # another) is seen: names and fields follow the message
    swapped = convert.joint_state_msg(2.0, [f"k{i}" for i in range(8)], rng.normal(size=8), None, None)
    moved = convert.joint_state_msg(3.0, [f"k{i}" for i in range(8)], None, rng.normal(size=8), None)
    for msg in (swapped, moved, swapped):
        want = convert.joint_state_arrays(msg)
        got = rawmsg.joint_state_arrays(serialize_message(msg), reader)
        assert got[1] == want[1] and all(_same(g, w) for g, w in zip(got[2:], want[2:]))
    assert reader.parsed == 8


def test_multidof_bytes_equal_rclpy_decoding():
    from rclpy.serialization import serialize_message
    from trajectory_msgs.msg import MultiDOFJointTrajectory

    from cablelab.ros import convert, rawmsg

    reader = rawmsg.RawReader(MultiDOFJointTrajectory)
    rng = np.random.default_rng(2)
    for vel, acc in ((True, True), (False, True), (True, False), (False, False)):
        q = rng.normal(size=4)
        msg = convert.multidof_msg(12.345, rng.normal(size=3), q / np.linalg.norm(q),
                                   rng.normal(size=3) if vel else None, rng.normal(size=3) if vel else None,
                                   rng.normal(size=3) if acc else None, rng.normal(size=3) if acc else None)
        want = convert.multidof_arrays(msg)
        got = rawmsg.multidof_arrays(serialize_message(msg), reader)
        assert got["t"] == pytest.approx(want["t"], abs=1e-9)
        assert all(_same(got[k], want[k]) for k in want if k != "t"), (vel, acc)
    empty = MultiDOFJointTrajectory()
    got = rawmsg.multidof_arrays(serialize_message(empty), reader)
    assert got["position"] is None and got["linear_acceleration"] is None


@settings(max_examples=200, deadline=None)
@given(st.binary(max_size=300))
def test_random_bytes_are_refused_with_value_error(data):
    from sensor_msgs.msg import JointState

    from cablelab.ros import rawmsg

    try:
        rawmsg.joint_state_arrays(b"\x00\x01\x00\x00" + data, rawmsg.RawReader(JointState))
    except ValueError:
        pass


def test_command_bytes_equal_rclpy_decoding():
    """Effort commands (Float64MultiArray whose label carries the answered stamp) decoded from
    bytes equal rclpy's decoding of the same bytes, for labelled, unlabelled, empty and
    multi-dimension layouts."""
    from rclpy.serialization import deserialize_message, serialize_message
    from std_msgs.msg import Float64MultiArray, MultiArrayDimension

    from cablelab.ros import convert, rawmsg

    rng = np.random.default_rng(3)
    cases = [convert.command_msg(rng.normal(size=8), 12.345678901), convert.float_array_msg([1.0, 2.0, 3.0]),
             convert.command_msg([], 1.0), convert.command_msg(rng.normal(size=1), None),
             convert.command_msg(rng.normal(size=5), 3.0, label="x" * 13)]
    two = convert.float_array_msg(rng.normal(size=6))
    two.layout.dim = [MultiArrayDimension(label="rows stamp=2.5", size=2, stride=6),
                      MultiArrayDimension(label="cols", size=3, stride=3)]
    two.layout.data_offset = 0
    cases.append(two)
    for msg in cases:
        raw = serialize_message(msg)
        back = deserialize_message(raw, Float64MultiArray)
        data, stamp = rawmsg.command_arrays(raw)
        assert np.array_equal(data, np.asarray(back.data, float))
        assert stamp == convert.command_stamp(back)
        # a message object goes through rclpy's path with the same result
        d2, s2 = rawmsg.command_arrays(msg)
        assert np.array_equal(d2, data) and s2 == stamp


@settings(max_examples=300, deadline=None)
@given(st.binary(max_size=200))
def test_random_bytes_are_not_commands_or_decode_within_bounds(data):
    from cablelab.ros import rawmsg

    try:
        values, stamp = rawmsg.command_arrays(b"\x00\x01\x00\x00" + data)
    except ValueError:
        return
    assert values.ndim == 1 and 8 * values.size <= len(data)
    assert stamp is None or np.isfinite(stamp)
