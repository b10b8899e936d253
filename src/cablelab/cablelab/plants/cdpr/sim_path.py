"""The simulator node's compiled per-period path (``cablelab/csrc/sim_path.c``, built and loaded by
:mod:`cablelab.native`).

In real time, a C thread steps the node's MuJoCo model on absolute deadlines with the newest
effort command (or the winch brakes), publishes the winch joint states, the cable tensions and
the reference through an rcl node of its own (``cable_sim_node_rt``: same topics, QoS and
serialised layout as the Python node's), and counts late, stale, braked and dropped steps
exactly as :class:`~.stepping.SimStepper` does. Each published sample goes into a lock-free
ring; the Python node drains it (:meth:`CompiledSimPath.drain`), copies the samples it needs into
its own :class:`~.sim.CdprSim`'s MjData (a mirror: the thread steps a copy, Python never touches
the thread's) and publishes the rest from there (/clock, pose, truth, /diagnostics, 3D view)
off the deadline path.

The Python path stays the oracle and the fallback: :func:`library` is None when
``CABLELAB_NATIVE=0`` or the library cannot be built, and lock-step runs in Python.
"""
from __future__ import annotations

import copy
import ctypes

import numpy as np

from ... import native
from ...ros.qos import PUBLISHER_DEPTH
from .mjcf import RUN_LENGTH

__all__ = ["COUNTS", "CompiledSimPath", "library"]

#: the C counters, in sim_path.h's order
COUNTS = ("steps", "commands", "rejected", "last_problem", "last_bad_length", "last_good_ns",
          "fallbacks", "fallbacks_running", "slack", "late", "dropped", "stale", "missed",
          "age1", "age2", "age3", "mass_changed", "done", "ring_lost", "publish_errors",
          "slow_joint_states", "slow_tensions", "slow_reference", "publish_max_ns", "wake_max_ns")
RING = 8192       # samples the Python side may fall behind (8 s at 1 kHz) before they are lost
_P, _L, _D, _I, _S = ctypes.c_void_p, ctypes.c_long, ctypes.c_double, ctypes.c_int, ctypes.c_char_p


def library():
    """The compiled library with its signatures, or None (Python path; see
    :func:`cablelab.native.unavailable_reason` with ``"sim_path"``)."""
    lib = native.load("sim_path")
    if lib is None or getattr(lib, "_sim_path_typed", False):
        return lib
    sig = {"sp_new": (_P, [_P, _P, _I, _I, _D, _L]), "sp_stride": (_L, [_P]),
           "sp_winches": (None, [_P, _P, _P, _P, _D, _D, _D, _D]),
           "sp_schedule": (None, [_P, _D, _D, _I, _D, _D, _D, _D, _P, ctypes.c_uint64]),
           "sp_tension_template": (None, [_P, _P, ctypes.c_size_t, _L, _L, _L, _L]),
           "sp_joint_template": (None, [_P, _P, ctypes.c_size_t, _L, _L, _L, _L, _L]),
           "sp_reference": (None, [_P, _P, ctypes.c_size_t, _L, _L, _L, _L, _L, _P, _L, _I]),
           "sp_ros": (_I, [_P, _S, _L, _P, _S, _S, _P, _S, _P, _S, _L]), "sp_error": (_S, [_P]),
           "sp_publish_now": (None, [_P]), "sp_start": (_I, [_P]), "sp_stop": (None, [_P]),
           "sp_running": (_I, [_P]), "sp_drain": (_L, [_P, _P, _L]), "sp_counts": (None, [_P, _P]),
           "sp_subscribers": (_I, [_P]), "sp_all_acked": (_I, [_P, _D]), "sp_free": (None, [_P]),
           "sp_run_commands": (None, [_P, _P, _L])}
    for name, (res, args) in sig.items():
        f = getattr(lib, name)
        f.restype, f.argtypes = res, args
    lib._sim_path_typed = True
    return lib


def type_support(msg_type) -> int:
    """The address of rclpy's own ``rosidl_message_type_support_t`` of ``msg_type``."""
    type(msg_type).__import_type_support__()
    api = ctypes.pythonapi
    api.PyCapsule_GetName.restype, api.PyCapsule_GetName.argtypes = ctypes.c_char_p, [ctypes.py_object]
    api.PyCapsule_GetPointer.restype = ctypes.c_void_p
    api.PyCapsule_GetPointer.argtypes = [ctypes.py_object, ctypes.c_char_p]
    cap = msg_type._TYPE_SUPPORT
    return api.PyCapsule_GetPointer(cap, api.PyCapsule_GetName(cap))


def _address(a: np.ndarray) -> int:
    return a.ctypes.data


class CompiledSimPath:
    """The C per-period path over ``stepper``'s simulation (a :class:`~.stepping.SimStepper` in
    real time, not yet stepped); its thread steps a copy of the MjData.

    Args:
        lib: :func:`library`.
        stepper: the node's stepper (its model, winches, brakes, schedule, reference).
        command_timeout: s wall after which the last command is stale (the brakes hold).

    Raises:
        ValueError: the stepper cannot be run by the C path (the message says why).
    """

    def __init__(self, lib, stepper, command_timeout: float):
        self.lib, self.stepper = lib, stepper
        sim, hw = stepper.sim, stepper.hw
        m = sim.model
        if m.nu < sim.n or sim.n > 64:
            raise ValueError(f"{sim.n} winches and {m.nu} actuators")
        if stepper.mass_change and not sim.model.body("platform").id:
            raise ValueError("no platform body")
        self.model, self.data = m, copy.copy(sim.data)          # the thread's own MjData
        self.stride = int(lib.sp_stride(m._address))
        self._h = lib.sp_new(m._address, self.data._address, sim.n, hw.nstep, stepper.rate, RING)
        if not self._h:
            raise ValueError("the C path refused the model")
        self._keep = []                                         # arrays the C side points into
        rq = np.ascontiguousarray(sim._reel_q, np.intc)
        rv = np.ascontiguousarray(sim._reel_v, np.intc)
        paid0 = np.ascontiguousarray(sim.cable_total - RUN_LENGTH, float)
        c = sim.desc.cdpr
        kp, kd = hw.brakes.gains
        lib.sp_winches(self._h, _address(rq), _address(rv), _address(paid0), float(sim.k), float(kp), float(kd),
                       float(c.drum_radius / c.gear_ratio))
        bias = np.ascontiguousarray(sim._bias, float)
        lib.sp_schedule(self._h, float(command_timeout), float(stepper.duration),
                        int(m.body("platform").id), float(stepper.mass_change), float(stepper.mass_change_time),
                        float(sim.truth.torque_noise), float(sim.truth.tension_noise), _address(bias),
                        int(sim.truth.seed) & (2 ** 64 - 1))
        self._mass_seen = 0
        self._buf = np.empty((RING, self.stride))
        self._counts = np.zeros(len(COUNTS), np.int64)
        self._buf_at, self._counts_at = _address(self._buf), _address(self._counts)
        self.started = False
        self.counts = dict.fromkeys(COUNTS, 0)

    def connect(self, outputs, js_topic: str, ten_topic: str, ref_topic: str, cmd_topic: str,
                domain_id: int) -> None:
        """Its rcl node in ROS domain ``domain_id``: the joint states, tensions and reference in
        the layout of ``outputs``' templates (:class:`~.nodes.outputs.CdprOutputs`), the
        commands on ``cmd_topic``.

        Raises:
            ValueError: rcl refused (its error)."""
        from sensor_msgs.msg import JointState
        from std_msgs.msg import Float64MultiArray
        from trajectory_msgs.msg import MultiDOFJointTrajectory

        lib, st = self.lib, self.stepper
        js = outputs.t_js
        sp = js.spans
        lib.sp_joint_template(self._h, bytes(js.buf), js.size, sp["header.stamp.sec"][0],
                              sp["header.stamp.nanosec"][0], sp["position"][0], sp["velocity"][0],
                              sp["effort"][0])
        ten = outputs.t_ten
        sp = ten.spans
        lib.sp_tension_template(self._h, bytes(ten.buf), ten.size, sp["header.stamp.sec"][0],
                                sp["header.stamp.nanosec"][0], sp["position"][0], sp["effort"][0])
        ts_ref = None
        if st.publish_reference:
            lead = st.reference_lead * st.rate
            if abs(lead - round(lead)) > 1e-6:
                raise ValueError(f"reference_lead {st.reference_lead:g} s is not a whole number of periods")
            rt = outputs.t_ref
            offs = [rt.spans[p + ".x"][0] for p in ("points[0].transforms[0].translation",
                                                    "points[0].velocities[0].linear",
                                                    "points[0].accelerations[0].linear")]
            for view in outputs.ref_views:                       # (checks they are contiguous)
                assert view.size == 3
            table = np.ascontiguousarray(np.hstack(st.reference._table))
            self._keep.append(table)
            lib.sp_reference(self._h, bytes(rt.buf), rt.size, rt.spans["header.stamp.sec"][0],
                             rt.spans["header.stamp.nanosec"][0], *offs, _address(table), len(table),
                             int(round(lead)))
            ts_ref = type_support(MultiDOFJointTrajectory)
        if lib.sp_ros(self._h, b"cable_sim_node_rt", int(domain_id), type_support(JointState), js_topic.encode(),
                      ten_topic.encode(), ts_ref,
                      ref_topic.encode(), type_support(Float64MultiArray), cmd_topic.encode(),
                      PUBLISHER_DEPTH):
            raise ValueError(lib.sp_error(self._h).decode(errors="replace"))

    # ------------------------------------------------------------------ running
    def publish_now(self) -> None:
        """Before :meth:`start`: the present state's joint states, tensions and reference."""
        self.lib.sp_publish_now(self._h)

    def start(self) -> None:
        if self.lib.sp_start(self._h):
            raise RuntimeError("the simulator's C thread did not start")
        self.started = True

    def close(self) -> None:
        """Stop the thread and free the C side (idempotent)."""
        if self._h:
            self.lib.sp_free(self._h)
            self._h = None

    def get_subscription_count(self) -> int:
        """Subscribers of the joint states (the start gate asks the publisher this)."""
        return int(self.lib.sp_subscribers(self._h)) if self._h else 0

    def all_acked(self, timeout: float = 0.0) -> bool:
        """Whether every reliable subscriber acknowledged every joint state, tension and reference
        sample (waiting up to ``timeout`` s)."""
        return bool(self.lib.sp_all_acked(self._h, float(timeout))) if self._h else True

    def run_commands(self, commands: np.ndarray) -> None:
        """Without ROS or clocks (tests): command row i drives step i answering the last state,
        a row whose first value is NaN: none came (the brakes hold)."""
        cmd = np.ascontiguousarray(commands, float)
        self.lib.sp_run_commands(self._h, _address(cmd), len(cmd))

    def drain(self) -> np.ndarray:
        """The samples published since the last call, (count, stride) (a view, valid until the
        next call): time, step, s of work, payloads put on, then qpos, qvel, actuator forces,
        sensors, tendon lengths."""
        if not self._h:
            return self._buf[:0]
        got = self.lib.sp_drain(self._h, self._buf_at, len(self._buf))
        return self._buf[:got]

    def mirror(self, row: np.ndarray) -> tuple[float, int, float, bool]:
        """Copy one drained sample into the stepper's own MjData (so its measurements, truth and
        3D view read it); (time, step, s of work, the payload was put on at this sample)."""
        m, d = self.model, self.stepper.sim.data
        d.time = row[0]
        i = 4
        for dest, size in ((d.qpos, m.nq), (d.qvel, m.nv), (d.actuator_force, m.nu),
                           (d.sensordata, m.nsensordata), (d.ten_length, m.ntendon)):
            dest[:] = row[i:i + size]
            i += size
        mass = int(row[3]) > self._mass_seen
        self._mass_seen = int(row[3])
        return float(row[0]), int(row[1]), float(row[2]), mass

    @property
    def mass_seen(self) -> int:
        """Payload changes the mirror has seen (:meth:`mirror`)."""
        return self._mass_seen

    def update(self, inputs=None) -> dict:
        """Read the C counters into the stepper's (what /diagnostics and the benchmarks report)
        and the ``effort_commands`` input of ``inputs`` (an
        :class:`~cablelab.ros.inputs.InputMonitor`); the counters as a dict."""
        if not self._h:
            return self.counts
        self.lib.sp_counts(self._h, self._counts_at)
        c = self.counts = dict(zip(COUNTS, self._counts.tolist()))
        s = self.stepper
        s.k, s.commands = c["steps"], c["commands"]
        s.fallbacks, s.fallbacks_running, s.slack_steps = c["fallbacks"], c["fallbacks_running"], c["slack"]
        s.late_steps, s.dropped_steps = c["late"], c["dropped"]
        s.stale_command_steps, s.missed_steps = c["stale"], c["missed"]
        s.command_age = [c["age1"], c["age2"], c["age3"]]
        s.done = bool(c["done"])
        if inputs is not None:
            st = inputs.inputs["effort_commands"]
            st.received, st.rejected = c["commands"], c["rejected"]
            st.last_time = c["last_good_ns"] * 1e-9 if c["commands"] else None
            st.last_problem = {1: "empty", 2: f"wrong length {c['last_bad_length']}, expected {st.length}",
                               3: "NaN or infinite value"}.get(c["last_problem"], "")
        return c

    def __del__(self):
        self.close()
