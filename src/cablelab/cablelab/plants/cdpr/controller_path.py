"""The ``pd_feedforward`` node's compiled state -> command path (``cablelab/csrc/controller_path.c``
through :mod:`ctypes`, built by :mod:`cablelab.native`).

Python plans the reference terms of each stamp (:meth:`LiveController.plan
<cablelab.plants.cdpr.live.LiveController.plan>`) and the feedforward of the present estimate
(:meth:`~cablelab.plants.cdpr.live.LiveController.planned_terms`) as soon as the reference comes,
and puts them in the library as rows keyed by stamp; a new estimate re-plans the rows not used
yet. A C thread (subscribing and publishing through the node's own rcl node) takes each joint state,
finds the row of its stamp and publishes :meth:`~cablelab.plants.cdpr.live.LiveController.
planned_law`'s torques, the same doubles, without Python. A state it cannot answer (bad values,
no row of its stamp) is handed to Python (:meth:`ControllerPath.handoff`), whose checks and law
decide and report as without this path. ROS-free apart from the thread the library runs.
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

_D = ctypes.c_void_p       # float64 arrays, passed by address (ndarray.ctypes.data)


def _bind(lib) -> None:
    if getattr(lib, "_cablelab_bound", False):
        return
    P, I, D = ctypes.c_void_p, ctypes.c_int, ctypes.c_double
    lib.cp_create.restype, lib.cp_create.argtypes = P, [I, I, D, D, D, D, D]
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
    lib._cablelab_bound = True


def _ptr(a: np.ndarray) -> int:
    return a.ctypes.data


class ControllerPath:
    """Rows of :class:`~cablelab.plants.cdpr.live.LiveController`'s plan in the compiled library,
    and its thread answering the joint states.

    Args:
        lib: the loaded library (:func:`load`).
        controller: the law whose plan and estimate the rows carry.
        row_wait: s a state newer than every row waits for its row before it goes to Python.
        keep: rows remembered for re-planning when an estimate comes.
    """

    def __init__(self, lib, controller: LiveController, row_wait: float = 0.005, keep: int = 64):
        _bind(lib)
        self.lib, self.controller = lib, controller
        cfg, g, d = controller.config, controller.config.gains, controller.desc
        self.n = len(d.cables)
        k = d.drum_radius / d.gear_ratio
        self.h = lib.cp_create(self.n, int(cfg.feedforward), g.kp, g.kd, k * g.min_tension, g.max_torque,
                               float(row_wait))
        if not self.h:
            raise ValueError(f"controller_path: cannot hold {self.n} winches")
        self.recent: ReferencePlan | None = None     # the rows put lately: re-planned by a new estimate
        self.keep = keep
        self._stats = np.zeros(12)
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
    def put(self, plan: ReferencePlan, rows=None, remember: bool = True) -> int:
        """Put the valid ``rows`` (default all) of ``plan`` with the present estimate (a row
        with a term that is not finite is left out: its states go to the Python path); returns
        how many the library kept (an older stamp it no longer holds is not)."""
        idx = np.flatnonzero(plan.valid) if rows is None else np.asarray(rows)[plan.valid[rows]]
        if idx.size == 0:
            return 0
        pd, ff, fric, _ = self.controller.planned_terms(plan, idx)
        finite = np.isfinite(pd).all(1) & np.isfinite(fric).all(1)
        if ff is not None:
            finite &= np.isfinite(ff).all(1)
        if not finite.all():        # (a reference far outside the workspace: the Python path says why)
            idx, pd, fric, ff = idx[finite], pd[finite], fric[finite], None if ff is None else ff[finite]
            if idx.size == 0:
                return 0
        t = np.ascontiguousarray(plan.t[idx], float)
        pd, fric = np.ascontiguousarray(pd), np.ascontiguousarray(fric)
        ff = None if ff is None else np.ascontiguousarray(ff)
        kept = self.lib.cp_put_rows(self.h, len(t), _ptr(t), _ptr(pd), None if ff is None else _ptr(ff), _ptr(fric))
        if remember:
            self._remember(plan, idx)
        return kept

    def _remember(self, plan: ReferencePlan, idx: np.ndarray) -> None:
        """Keep the newest :attr:`keep` rows put and not answered yet, as one plan, for
        :meth:`replan`."""
        r = self.recent
        parts = [(plan.t[idx], plan.pd[idx], plan.friction[idx], None if plan.ff is None else plan.ff[idx])]
        if r is not None:
            last = self.stats()["last_stamp"]
            todo = slice(None) if not np.isfinite(last) else r.t > last
            parts.insert(0, (r.t[todo], r.pd[todo], r.friction[todo], None if r.ff is None else r.ff[todo]))
        t, pd, fric = (np.concatenate([p[k] for p in parts])[-self.keep:] for k in range(3))
        ff = None if plan.ff is None else np.concatenate([p[3] for p in parts])[-self.keep:]
        self.recent = ReferencePlan(t, (None, None, None), np.ones(len(t), bool), pd, fric, ff)

    def replan(self) -> int:
        """Put again, with the present estimate, the remembered rows not answered yet."""
        r = self.recent
        if r is None:
            return 0
        last = self.stats()["last_stamp"]
        todo = np.arange(len(r.t)) if not np.isfinite(last) else np.flatnonzero(r.t > last)
        return self.put(r, todo, remember=False) if todo.size else 0

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
        ``publish_max_ms`` (the longest)."""
        self.lib.cp_stats(self.h, _ptr(self._stats))
        s = self._stats
        return {"commanded": int(s[0]), "handed_off": int(s[1]), "waited": int(s[2]), "publish_failed": int(s[3]),
                "running": int(s[4]), "last_stamp": float(s[5]), "last_wall": float(s[6]), "taken": int(s[7]),
                "wakes": int(s[8]), "last_taken": float(s[9]), "publish_slow": int(s[10]),
                "publish_max_ms": 1000.0 * float(s[11])}

    def latencies(self) -> np.ndarray:
        """Take -> published times (s) of the commands since the last call."""
        k = self.lib.cp_latencies(self.h, _ptr(self._lat), len(self._lat))
        return self._lat[:k].copy()

    def close(self) -> None:
        """Stop the thread and free the library's state (idempotent)."""
        if self.h:
            h, self.h = self.h, None
            self.lib.cp_destroy(h)
