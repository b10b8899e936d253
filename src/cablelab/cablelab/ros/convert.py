"""Message <-> numpy conversions for the contract types (one message at a time, for nodes).

Times are seconds (float) <-> builtin_interfaces/Time. Empty float64[] fields come back as
``None``; arrays go out as float64. Batch conversion of recorded data lives in
:mod:`cablelab.bags` (vectorised); these are for live callbacks.
"""
from __future__ import annotations

import importlib

import numpy as np
from builtin_interfaces.msg import Time
from geometry_msgs.msg import InertiaStamped, PoseStamped, Transform, Twist
from rosgraph_msgs.msg import Clock
from sensor_msgs.msg import JointState
from std_msgs.msg import Float64MultiArray, MultiArrayDimension, String
from trajectory_msgs.msg import JointTrajectory, JointTrajectoryPoint, MultiDOFJointTrajectory, \
    MultiDOFJointTrajectoryPoint


def message_class(msgtype: str):
    """The rclpy message class of ``'pkg/msg/Name'`` (CablelabError-free: raises ValueError)."""
    try:
        pkg, kind, name = msgtype.split("/")
        return getattr(importlib.import_module(f"{pkg}.{kind}"), name)
    except (ValueError, ImportError, AttributeError):
        raise ValueError(f"unknown message type {msgtype!r}") from None


def to_stamp(t: float) -> Time:
    """Seconds -> builtin_interfaces/Time (nanosecond rounding)."""
    ns = int(round(float(t) * 1e9))
    return Time(sec=ns // 1_000_000_000, nanosec=ns % 1_000_000_000)


def from_stamp(stamp) -> float:
    """builtin_interfaces/Time -> seconds."""
    return stamp.sec + stamp.nanosec * 1e-9


def _arr(values) -> np.ndarray | None:
    a = np.asarray(values, dtype=float)
    return a if a.size else None


def joint_state_msg(t: float, names, position=None, velocity=None, effort=None,
                    frame_id: str = "") -> JointState:
    """sensor_msgs/JointState; fields given as None stay empty."""
    msg = JointState()
    msg.header.stamp = to_stamp(t)
    msg.header.frame_id = frame_id
    msg.name = [str(n) for n in names]
    for field, values in (("position", position), ("velocity", velocity), ("effort", effort)):
        if values is not None:
            setattr(msg, field, np.asarray(values, dtype=float).ravel().tolist())
    return msg


def joint_state_arrays(msg: JointState):
    """(t s, names, position, velocity, effort) with None for empty fields."""
    return (from_stamp(msg.header.stamp), list(msg.name), _arr(msg.position), _arr(msg.velocity),
            _arr(msg.effort))


def named_positions(msg: JointState, names) -> np.ndarray | None:
    """Positions of the joints ``names`` in a JointState (any order, other joints ignored), or
    None when one is missing or the names and positions differ in number."""
    _, got, q, _, _ = joint_state_arrays(msg)
    if q is None or not set(names) <= set(got) or len(got) != q.size:
        return None
    return np.array([q[got.index(n)] for n in names])


def float_array_msg(data) -> Float64MultiArray:
    """std_msgs/Float64MultiArray with an empty layout (ros2_control forward-command style)."""
    msg = Float64MultiArray()
    msg.data = np.asarray(data, dtype=float).ravel().tolist()
    return msg


def float_array(msg: Float64MultiArray) -> np.ndarray:
    return np.asarray(msg.data, dtype=float)


def command_msg(data, stamp: float | None = None, label: str = "command") -> Float64MultiArray:
    """An effort command (std_msgs/Float64MultiArray, ros2_control forward-command style) that
    says which state it answers: ``layout.dim[0].label = '<label> stamp=<t>'`` (t = header stamp
    of that state, s). A lock-step simulator matches it (:func:`command_stamp`); everyone else
    just reads ``data``. Without ``stamp`` the layout is empty."""
    msg = float_array_msg(data)
    if stamp is not None:
        n = len(msg.data)
        msg.layout.dim = [MultiArrayDimension(label=f"{label} stamp={float(stamp):.9f}", size=n, stride=n)]
    return msg


def command_stamp(msg: Float64MultiArray) -> float | None:
    """The stamp (s) of the state a command answers (see :func:`command_msg`), None if it does
    not say (a foreign controller) or says something unreadable."""
    return label_stamp(msg.layout.dim[0].label) if msg.layout.dim else None


def label_stamp(label: str) -> float | None:
    """The stamp in a command label ``'<label> stamp=<t>'`` (s), None if it has none or it is
    unreadable or not finite."""
    if "stamp=" not in label:
        return None
    try:
        t = float(label.split("stamp=", 1)[1])
    except ValueError:
        return None
    return t if np.isfinite(t) else None


def same_stamp(a: float | None, b: float | None, tol: float = 1e-6) -> bool:
    """True if two stamps (s) name the same sample (both given, within ``tol`` s)."""
    return a is not None and b is not None and abs(a - b) < tol


def pose_msg(t: float, position, quaternion, frame_id: str = "world") -> PoseStamped:
    """geometry_msgs/PoseStamped from position (3,) and quaternion (4,) x, y, z, w."""
    msg = PoseStamped()
    msg.header.stamp = to_stamp(t)
    msg.header.frame_id = frame_id
    p, q = np.asarray(position, float), np.asarray(quaternion, float)
    msg.pose.position.x, msg.pose.position.y, msg.pose.position.z = map(float, p)
    o = msg.pose.orientation
    o.x, o.y, o.z, o.w = map(float, q)
    return msg


def pose_arrays(msg: PoseStamped):
    """(t s, position (3,), quaternion (4,) x, y, z, w)."""
    p, o = msg.pose.position, msg.pose.orientation
    return from_stamp(msg.header.stamp), np.array([p.x, p.y, p.z]), np.array([o.x, o.y, o.z, o.w])


def inertia_msg(t: float, m: float, com, frame_id: str = "platform") -> InertiaStamped:
    """geometry_msgs/InertiaStamped with mass (kg) and centre of mass (m); inertia tensor 0."""
    msg = InertiaStamped()
    msg.header.stamp = to_stamp(t)
    msg.header.frame_id = frame_id
    msg.inertia.m = float(m)
    c = np.asarray(com, float)
    msg.inertia.com.x, msg.inertia.com.y, msg.inertia.com.z = map(float, c)
    return msg


def inertia_arrays(msg: InertiaStamped):
    """(t s, m kg, com (3,) m)."""
    c = msg.inertia.com
    return from_stamp(msg.header.stamp), float(msg.inertia.m), np.array([c.x, c.y, c.z])


def joint_trajectory_msg(t: float, names, positions, velocities=None, accelerations=None) -> JointTrajectory:
    """trajectory_msgs/JointTrajectory with one point (time_from_start 0)."""
    msg = JointTrajectory()
    msg.header.stamp = to_stamp(t)
    msg.joint_names = [str(n) for n in names]
    pt = JointTrajectoryPoint()
    for field, values in (("positions", positions), ("velocities", velocities),
                          ("accelerations", accelerations)):
        if values is not None:
            setattr(pt, field, np.asarray(values, dtype=float).ravel().tolist())
    msg.points = [pt]
    return msg


def joint_trajectory_point(msg: JointTrajectory):
    """(t s, names, positions, velocities, accelerations) of the first point (None if empty;
    positions None too when the message has no point)."""
    t = from_stamp(msg.header.stamp)
    if not msg.points:
        return t, list(msg.joint_names), None, None, None
    pt = msg.points[0]
    return t, list(msg.joint_names), _arr(pt.positions), _arr(pt.velocities), _arr(pt.accelerations)


def reference_point(msg: JointTrajectory, joints=None):
    """``(q, qd, qdd)`` of a reference's first point, velocities and accelerations that are
    missing or of another length than the positions as zeros; None when it has no positions or
    (``joints`` given) names other joints."""
    _, names, q, qd, qdd = joint_trajectory_point(msg)
    if q is None or (joints is not None and names != list(joints)):
        return None
    return (q,) + tuple(x if x is not None and x.size == q.size else np.zeros_like(q) for x in (qd, qdd))


def multidof_msg(t: float, position, quaternion, linear_velocity=None, angular_velocity=None,
                 linear_acceleration=None, angular_acceleration=None,
                 joint_name: str = "platform") -> MultiDOFJointTrajectory:
    """trajectory_msgs/MultiDOFJointTrajectory, one joint, one point (CONTRACT /cdpr/reference)."""
    msg = MultiDOFJointTrajectory()
    msg.header.stamp = to_stamp(t)
    msg.header.frame_id = "world"
    msg.joint_names = [joint_name]
    pt = MultiDOFJointTrajectoryPoint()
    tf = Transform()
    tf.translation.x, tf.translation.y, tf.translation.z = map(float, np.asarray(position, float))
    r = tf.rotation
    r.x, r.y, r.z, r.w = map(float, np.asarray(quaternion, float))
    pt.transforms = [tf]
    for field, lin, ang in (("velocities", linear_velocity, angular_velocity),
                            ("accelerations", linear_acceleration, angular_acceleration)):
        if lin is not None or ang is not None:
            tw = Twist()
            for vec, values in ((tw.linear, lin), (tw.angular, ang)):
                if values is not None:
                    vec.x, vec.y, vec.z = map(float, np.asarray(values, float))
            setattr(pt, field, [tw])
    msg.points = [pt]
    return msg


def multidof_arrays(msg: MultiDOFJointTrajectory) -> dict:
    """First point, first joint: {"t", "position", "quaternion", "linear_velocity",
    "angular_velocity", "linear_acceleration", "angular_acceleration"} (None if absent)."""
    out = {"t": from_stamp(msg.header.stamp), "position": None, "quaternion": None,
           "linear_velocity": None, "angular_velocity": None,
           "linear_acceleration": None, "angular_acceleration": None}
    if not msg.points or not msg.points[0].transforms:
        return out
    pt = msg.points[0]
    tr, ro = pt.transforms[0].translation, pt.transforms[0].rotation
    out["position"] = np.array([tr.x, tr.y, tr.z])
    out["quaternion"] = np.array([ro.x, ro.y, ro.z, ro.w])
    for field, prefix in (("velocities", "velocity"), ("accelerations", "acceleration")):
        seq = getattr(pt, field)
        if seq:
            lin, ang = seq[0].linear, seq[0].angular
            out[f"linear_{prefix}"] = np.array([lin.x, lin.y, lin.z])
            out[f"angular_{prefix}"] = np.array([ang.x, ang.y, ang.z])
    return out


def clock_msg(t: float) -> Clock:
    """rosgraph_msgs/Clock holding t (s)."""
    msg = Clock()
    msg.clock = to_stamp(t)
    return msg


def string_msg(text: str) -> String:
    msg = String()
    msg.data = str(text)
    return msg


def imu_msg(t: float, quaternion, angular_velocity, linear_acceleration=None,
            frame_id: str = "imu"):
    """sensor_msgs/Imu: orientation (x, y, z, w; sensor frame to world), angular velocity
    (rad/s, sensor frame), linear acceleration (m/s^2, sensor frame, specific force). A field
    given as None is marked unavailable (covariance[0] = -1, sensor_msgs convention)."""
    from sensor_msgs.msg import Imu

    msg = Imu()
    msg.header.stamp = to_stamp(t)
    msg.header.frame_id = frame_id
    for name, values in (("orientation", quaternion), ("angular_velocity", angular_velocity),
                         ("linear_acceleration", linear_acceleration)):
        if values is None:
            getattr(msg, f"{name}_covariance")[0] = -1.0
            continue
        v = np.asarray(values, float)
        target = getattr(msg, name)
        target.x, target.y, target.z = map(float, v[:3])
        if name == "orientation":
            target.w = float(v[3])
    return msg


def imu_arrays(msg):
    """(t s, quaternion (4,) x, y, z, w, angular velocity (3,), linear acceleration (3,)); a field
    marked unavailable (covariance[0] = -1) comes back as None."""
    out = [from_stamp(msg.header.stamp)]
    for name in ("orientation", "angular_velocity", "linear_acceleration"):
        if getattr(msg, f"{name}_covariance")[0] == -1.0:
            out.append(None)
            continue
        v = getattr(msg, name)
        out.append(np.array([v.x, v.y, v.z, v.w]) if name == "orientation" else np.array([v.x, v.y, v.z]))
    return tuple(out)
