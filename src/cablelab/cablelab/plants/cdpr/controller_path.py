"""The ``pd_feedforward`` node's compiled state -> command path (``cablelab/csrc/controller_path.c``
through :mod:`ctypes`, built by :mod:`cablelab.native`).

Python plans the reference terms of each stamp (:meth:`LiveController.plan
<cablelab.plants.cdpr.live.LiveController.plan>`: the PD part, the four feedforward tension rows,
the friction compensation) as soon as the reference comes and puts them in the library as rows
keyed by stamp; each estimate gives the library its weights (:meth:`~cablelab.plants.cdpr.live.
LiveController.estimate_weights`), so it changes no row. A C thread (subscribing and publishing
through the node's own rcl node) takes each joint state, finds the row of its stamp and publishes
:meth:`~cablelab.plants.cdpr.live.LiveController.planned_law`'s torques (the same doubles up to
the order of the feedforward's four-term sum) without Python. A state it cannot answer (bad
values, no row of its stamp) is handed to Python (:meth:`ControllerPath.handoff`), whose checks
and law decide and report as without this path. Once the references come far ahead of the
states (:meth:`ControllerPath.follow_references`) the thread also takes them, after each
command, and Python reads them in blocks (:meth:`ControllerPath.references`) to plan their rows.
ROS-free apart from the thread the library runs.
"""
from __future__ import annotations

import atexit
import ctypes

import numpy as np

from ... import native
from .live import LiveController, ReferencePlan

__all__ = ["ControllerPath", "LIBRARY"]

LIBRARY = "controller_path"
MAX_HANDOFF = 256          # values of a handed-off state read back (the library keeps as many)
OK, NO_ROW, BAD_STATE = 0, 1, 2
REF_COLUMNS = 15           # t, has position, position (3), quaternion x y z w, velocity (3), acceleration (3)
MAX_REFERENCES = 2048      # rows the library keeps until they are read

_D = ctypes.c_void_p       # float64 arrays, passed by address (ndarray.ctypes.data)


def _bind(lib) -> None:
    if getattr(lib, "_cablelab_bound", False):
        return
    P, I, D = ctypes.c_void_p, ctypes.c_int, ctypes.c_double
    lib.cp_create.restype, lib.cp_create.argtypes = P, [I, I, D, D, D, D, D, D, D, D]
    lib.cp_set_estimate.restype, lib.cp_set_estimate.argtypes = None, [P, D, D, D, D, D]
    lib.cp_destroy.restype, lib.cp_destroy.argtypes = None, [P]
    lib.cp_put_rows.restype, lib.cp_put_rows.argtypes = I, [P, I, _D, _D, _D, _D]
    lib.cp_law.restype, lib.cp_law.argtypes = I, [P, D, _D, I, _D, I, _D]
    lib.cp_handoff.restype = I
    lib.cp_handoff.argtypes = [P, _D, _D, _D, ctypes.POINTER(I), _D, ctypes.POINTER(I), I]
    lib.cp_stats.restype, lib.cp_stats.argtypes = None, [P, _D]
    lib.cp_latencies.restype, lib.cp_latencies.argtypes = I, [P, _D, I]
    lib.cp_start.restype = I
    lib.cp_start.argtypes = [P, P, P, ctypes.c_char_p, ctypes.c_char_p, I, ctypes.c_char_p]
    lib.cp_stop.restype, lib.cp_stop.argtypes = None, [P]
    lib.cp_error.restype, lib.cp_error.argtypes = ctypes.c_char_p, [P]
    lib.cp_follow_references.restype, lib.cp_follow_references.argtypes = I, [P, ctypes.c_char_p, I]
    lib.cp_references.restype, lib.cp_references.argtypes = I, [P, _D, I]
    lib._cablelab_bound = True


def _ptr(a: np.ndarray) -> int:
    return a.ctypes.data


class ControllerPath:
    """Rows of :class:`~cablelab.plants.cdpr.live.LiveController`'s plan in the compiled library,
    and its thread answering the joint states.

    Args:
        lib: the loaded library (:func:`load`).
        controller: the law whose plan the rows carry and whose estimate (:meth:`estimate`) weighs
            their feedforward.
        row_wait: s a state newer than every row waits for its row before it goes to Python.
    """

    def __init__(self, lib, controller: LiveController, row_wait: float = 0.005):
        _bind(lib)
        self.lib, self.controller = lib, controller
        cfg, g, d = controller.config, controller.config.gains, controller.desc
        self.n = len(d.cables)
        self.h = lib.cp_create(self.n, int(cfg.feedforward), g.kp, g.kd, d.drum_radius / d.gear_ratio, g.min_tension,
                               g.max_torque, float(row_wait), cfg.nominal_mass, cfg.estimate_timeout)
        if not self.h:
            raise ValueError(f"controller_path: cannot hold {self.n} winches")
        self.estimate()
        self._stats = np.zeros(14)
        self._refs = np.zeros((MAX_REFERENCES, REF_COLUMNS))
        self._lat = np.zeros(4096)
        self._q, self._qd = np.zeros(MAX_HANDOFF), np.zeros(MAX_HANDOFF)
        self._t, self._wall = np.zeros(1), np.zeros(1)
        self._nq, self._nqd = ctypes.c_int(), ctypes.c_int()
        atexit.register(self.close)

    @classmethod
    def load(cls, controller: LiveController, row_wait: float = 0.005) -> "ControllerPath | None":
        """The compiled path for ``controller``, or None (no compiler, ``CABLELAB_NATIVE=0``:
        :func:`cablelab.native.unavailable_reason` says why)."""
        lib = native.load(LIBRARY)
        return None if lib is None else cls(lib, controller, row_wait)

    # ------------------------------------------------------------------ rows
    def put(self, plan: ReferencePlan, rows=None) -> int:
        """Put the valid ``rows`` (default all) of ``plan`` (a row with a term that is not finite
        is left out: its states go to the Python path); returns how many the library kept (an
        older stamp it no longer holds is not)."""
        idx = np.flatnonzero(plan.valid) if rows is None else np.asarray(rows)[plan.valid[rows]]
        finite = np.isfinite(plan.pd[idx]).all(1) & np.isfinite(plan.friction[idx]).all(1)
        if plan.ff is not None:
            finite &= np.isfinite(plan.ff[idx]).all((1, 2))
        idx = idx[finite]           # (a reference far outside the workspace: the Python path says why)
        if idx.size == 0:
            return 0
        t = np.ascontiguousarray(plan.t[idx], float)
        pd, fric = np.ascontiguousarray(plan.pd[idx], float), np.ascontiguousarray(plan.friction[idx], float)
        ff = None if plan.ff is None else np.ascontiguousarray(plan.ff[idx], float)
        return self.lib.cp_put_rows(self.h, len(t), _ptr(t), _ptr(pd), None if ff is None else _ptr(ff), _ptr(fric))

    def estimate(self) -> None:
        """Give the library the controller's present estimate (:meth:`LiveController.estimate_weights
        <cablelab.plants.cdpr.live.LiveController.estimate_weights>`): every row answered from now
        on weighs its feedforward with it."""
        t_est, c = self.controller.estimate_weights()
        self.lib.cp_set_estimate(self.h, t_est, *map(float, c))

    # ------------------------------------------------------------------ the law
    def law(self, t: float, q, qdot) -> tuple[int, np.ndarray | None]:
        """(OK, torques (n,)), (NO_ROW, None) or (BAD_STATE, None): what the thread computes for
        the motor state of stamp ``t``."""
        q = np.ascontiguousarray(q, float).ravel()
        qd = np.ascontiguousarray(qdot, float).ravel()
        out = np.empty(self.n)
        rc = self.lib.cp_law(self.h, float(t), _ptr(q), q.size, _ptr(qd), qd.size, _ptr(out))
        return rc, (out if rc == OK else None)

    # ------------------------------------------------------------------ the thread
    def start(self, node, state_topic: str, command_topic: str, depth: int, label: str) -> str | None:
        """Start the thread answering ``state_topic`` on ``command_topic`` (keep-last ``depth``,
        labels ``'<label> stamp=<t>'``) through the rcl node of the rclpy ``node`` (:meth:`close`
        before it is destroyed); None, or why not."""
        rc = self.lib.cp_start(self.h, node.handle.pointer, node.context.handle.pointer, state_topic.encode(),
                               command_topic.encode(), int(depth), label.encode())
        return None if rc == 0 else (self.lib.cp_error(self.h) or b"").decode() or "failed"

    def follow_references(self, topic: str, depth: int) -> str | None:
        """From now on the thread also takes the reference samples of ``topic`` (keep-last
        ``depth``) for :meth:`references`; None, or why not."""
        rc = self.lib.cp_follow_references(self.h, topic.encode(), int(depth))
        return None if rc == 0 else (self.lib.cp_error(self.h) or b"").decode() or "failed"

    def references(self) -> np.ndarray:
        """The reference samples the thread took since the last call, oldest first: (k,
        :data:`REF_COLUMNS`) rows ``t, has position (1/0), position (3), quaternion x y z w,
        linear velocity (3), linear acceleration (3)`` of the first point's first joint (NaN where
        the message has none), as :func:`cablelab.ros.convert.multidof_arrays` reads them."""
        k = self.lib.cp_references(self.h, _ptr(self._refs), MAX_REFERENCES)
        return self._refs[:k].copy()

    def handoff(self):
        """The newest state the thread left to Python since the last call: ``(t, wall, q, qdot)``
        (``wall``: time.monotonic() when it came; arrays of the lengths received, at most
        :data:`MAX_HANDOFF`), or None."""
        if not self.lib.cp_handoff(self.h, _ptr(self._t), _ptr(self._wall), _ptr(self._q), ctypes.byref(self._nq),
                                   _ptr(self._qd), ctypes.byref(self._nqd), MAX_HANDOFF):
            return None
        nq, nqd = min(self._nq.value, MAX_HANDOFF), min(self._nqd.value, MAX_HANDOFF)
        return float(self._t[0]), float(self._wall[0]), self._q[:nq].copy(), self._qd[:nqd].copy()

    def stats(self) -> dict:
        """Counts of the thread: ``commanded``, ``handed_off``, ``waited`` (for a row),
        ``publish_failed``, ``running`` (1, 0 stopped, -1 failed), ``last_stamp`` and
        ``last_wall`` of the last command (NaN before), ``taken`` (states), ``wakes`` (of the
        thread), ``last_taken`` (stamp of the last state taken, NaN before), ``publish_slow``
        (command publishes that took over 0.2 ms: the thread held up inside DDS),
        ``publish_max_ms`` (the longest), ``references`` (samples the thread took),
        ``references_lost`` (taken but not read by :meth:`references` before the library's ring
        wrapped)."""
        self.lib.cp_stats(self.h, _ptr(self._stats))
        s = self._stats
        return {"commanded": int(s[0]), "handed_off": int(s[1]), "waited": int(s[2]), "publish_failed": int(s[3]),
                "running": int(s[4]), "last_stamp": float(s[5]), "last_wall": float(s[6]), "taken": int(s[7]),
                "wakes": int(s[8]), "last_taken": float(s[9]), "publish_slow": int(s[10]),
                "publish_max_ms": 1000.0 * float(s[11]), "references": int(s[12]),
                "references_lost": int(s[13])}

    def latencies(self) -> np.ndarray:
        """Take -> published times (s) of the commands since the last call."""
        k = self.lib.cp_latencies(self.h, _ptr(self._lat), len(self._lat))
        return self._lat[:k].copy()

    def close(self) -> None:
        """Stop the thread and free the library's state (idempotent)."""
        if self.h:
            h, self.h = self.h, None
            self.lib.cp_destroy(h)
