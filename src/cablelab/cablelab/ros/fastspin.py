"""A lean executor for one node with 1 kHz streams: one prebuilt wait set, every queued message
taken in one wake-up, callbacks called directly.

rclpy's ``SingleThreadedExecutor.spin_once`` rebuilds its wait set, wraps every callback in a
Task/coroutine and wakes up once per message: about 65 us of CPU per message on the project's
machine, more than the estimator's own math. :class:`FastExecutor` keeps what a data-flow node
needs and drops the rest:

* the wait set is allocated once for the node's subscriptions and timers (re-filled, not
  re-allocated, before each wait: rcl clears the entries that were not ready);
* every ready subscription is drained (``take_message`` until empty), one sample per topic per
  round in the order the node created its subscriptions (so a backlog on two topics keeps its
  interleaving), each message going straight to its callback;
* ready timers are called (``call_timer`` then the callback) after the subscriptions were
  drained: a timer sees every sample that came before it woke (e.g. a simulator's deadline sees
  the command that arrived with it);
* entities created after :meth:`add_node` (e.g. a subscription made in a callback) are picked up
  on the next wait (the wait set is rebuilt when the node's entity lists change);
* *polled* subscriptions (:func:`poll`) are left out of the wait set: their samples wake nobody
  and wait in the DDS queue until the node takes them with :func:`drain` (e.g. a controller takes
  the reference and the estimate when a state arrives; an estimator takes its 1 kHz inputs in
  batches on a timer). Every Python wake-up costs tens of microseconds of CPU at 1 kHz, so a node
  that wakes once per cycle instead of three times leaves the CPU to the loop's critical path;
* *deferred* timers (:func:`defer`) are left out of the wait set too: the node calls the due ones
  itself with :func:`run_deferred` where they cannot delay its deadline work (e.g. a simulator's
  /diagnostics and 3D view right after a step's state went out, not just before the next step).

Services are answered (synchronous callbacks). Not serviced: clients, guard conditions and
waitables (the QoS event handlers that log incompatible-QoS warnings). Use it for nodes that have
no clients or guard conditions (:func:`supports` says whether a node qualifies). Same interface as
the part of rclpy's executor the runner uses: ``add_node``, ``spin_once(timeout_sec)``.
Measured gain: docs/benchmarks.md, CDPR section.
"""
from __future__ import annotations

from contextlib import ExitStack

from rclpy.exceptions import InvalidHandle

__all__ = ["FastExecutor", "supports", "set_realtime_priority", "set_cpu_affinity", "set_background",
           "set_latency_slice", "set_idle_class", "yield_to_compiled", "poll", "polled", "drain", "take_newest", "defer", "deferred",
           "run_deferred"]


def set_realtime_priority(priority: int) -> str:
    """Put every thread of this process (the Python thread and the DDS threads already running)
    under SCHED_FIFO at ``priority`` (1-99), as a real-time robot deployment would; threads
    created later inherit it. Only for event-driven nodes: a busy loop under SCHED_FIFO starves
    the machine (the kernel's RT throttling still leaves it 5 %). Returns a one-line result for
    the log ("SCHED_FIFO 10 on 12 threads", or why not: no permission, not Linux)."""
    import os

    if priority <= 0:
        return "normal scheduling"
    try:
        tids = [int(t) for t in os.listdir("/proc/self/task")]
        param = os.sched_param(int(priority))
        for tid in tids:
            os.sched_setscheduler(tid, os.SCHED_FIFO, param)
    except (OSError, AttributeError) as exc:
        return f"SCHED_FIFO {priority} not available ({exc}): normal scheduling"
    return f"SCHED_FIFO {priority} on {len(tids)} threads"


def set_cpu_affinity(cpus) -> str:
    """Pin every thread of this process (and the threads they start later) to ``cpus`` (CPU
    numbers), as a real-time deployment places a control loop's processes on their own cores;
    no privilege is needed. Returns a one-line result for the log."""
    import os

    cpus = sorted({int(c) for c in cpus})
    if not cpus:
        return "no CPU affinity"
    try:
        tids = [int(t) for t in os.listdir("/proc/self/task")]
        for tid in tids:
            os.sched_setaffinity(tid, cpus)
    except (OSError, AttributeError, ValueError) as exc:
        return f"CPU affinity {cpus} not available ({exc})"
    return f"CPU affinity {cpus} on {len(tids)} threads"


def set_background(niceness: int) -> str:
    """Lower this process's CPU priority by ``niceness`` (1-19), for a node that is not on the
    loop's critical path (e.g. a slowly varying estimate): the process's nice value and, where
    Linux groups each session's processes (autogroup, on by default on desktops), the nice value
    of its group, which is what the scheduler weighs against other sessions. Lowering a priority
    needs no privilege. Returns a one-line result for the log."""
    import os

    niceness = max(0, min(int(niceness), 19))
    if niceness == 0:
        return "normal priority"
    done = []
    try:
        for tid in (int(t) for t in os.listdir("/proc/self/task")):
            os.setpriority(os.PRIO_PROCESS, tid, max(os.getpriority(os.PRIO_PROCESS, tid), niceness))
        done.append(f"nice {niceness}")
    except (OSError, AttributeError) as exc:
        done.append(f"nice not available ({exc})")
    try:
        with open("/proc/self/autogroup", "w") as f:
            f.write(str(niceness))
        done.append("autogroup too")
    except OSError:
        pass
    return ", ".join(done)


def yield_to_compiled(niceness: int = 10, idle: bool = False) -> str:
    """Lower the CALLING thread's CPU priority by ``niceness`` (its own nice value; the process's
    other threads keep theirs): for a node's Python thread once a compiled thread carries the
    node's deadline path (:mod:`cablelab.native`), so that on a crowded machine the scheduler
    gives the compiled thread and the DDS threads that feed it the CPU first, and the Python
    thread (publishing what is off the deadline path) what is left. Call it after starting the
    compiled thread (a thread inherits its creator's nice value). ``idle``: the SCHED_IDLE class
    instead (preempted at once by any ordinary thread, so it never delays the compiled one, but
    starved on a machine busy with other work: for an otherwise idle machine). No privilege is
    needed. Returns a one-line result for the log."""
    import os
    import threading

    tid = threading.get_native_id()
    if idle:
        try:
            os.sched_setscheduler(tid, os.SCHED_IDLE, os.sched_param(0))
            return "the Python thread in SCHED_IDLE"
        except (OSError, AttributeError) as exc:
            return f"SCHED_IDLE not available ({exc})"
    try:
        os.setpriority(os.PRIO_PROCESS, tid, max(os.getpriority(os.PRIO_PROCESS, tid), int(niceness)))
    except (OSError, AttributeError) as exc:
        return f"nice not available ({exc})"
    return f"the Python thread at nice {os.getpriority(os.PRIO_PROCESS, tid)}"


def set_idle_class() -> str:
    """Run every thread of this process (and the threads it starts later) in Linux's SCHED_IDLE
    class: the scheduler's class for background work, which gets the CPU only when no ordinary
    task wants it and is preempted at once when one wakes up (a nice-19 task, by contrast, still
    finishes its time slice first, ~1-4 ms on a 250 Hz kernel). For a node off a 1 kHz loop's
    critical path, e.g. an estimator whose output is low-pass filtered by its consumer. No
    privilege is needed. The kernel weighs processes of different sessions as groups
    (autogroup), so this acts against the loop's processes when they run in one session, as
    ``ros2 launch`` and :class:`cablelab.ros.launch.Launcher` start them. Returns a one-line
    result for the log."""
    import os

    try:
        tids = [int(t) for t in os.listdir("/proc/self/task")]
        for tid in tids:
            os.sched_setscheduler(tid, os.SCHED_IDLE, os.sched_param(0))
    except (OSError, AttributeError) as exc:
        return f"SCHED_IDLE not available ({exc})"
    return f"SCHED_IDLE on {len(tids)} threads"


def set_latency_slice(seconds: float) -> str:
    """Ask Linux's EEVDF scheduler (kernel >= 6.12) for a short time slice, ``seconds`` (0.1-100
    ms), on every thread of this process (threads started later inherit it). EEVDF gives each
    runnable task a virtual deadline one slice after it became eligible and runs the earliest
    deadline first; a task that asks for a short slice gets an early deadline when it wakes and
    preempts a task running a long (default ~1-3 ms) slice at once, instead of waiting for that
    slice to end. That is the latency knob of ordinary (SCHED_OTHER) scheduling: no privilege,
    the task's CPU share (its nice weight) unchanged. For the threads of a 1 kHz loop that wake,
    work ~0.1-0.3 ms and sleep. Returns a one-line result for the log (or why not: older kernel,
    not Linux)."""
    import ctypes
    import os
    import platform
    import struct

    ns = int(round(float(seconds) * 1e9))
    if ns <= 0:
        return "default time slice"
    ns = min(max(ns, 100_000), 100_000_000)
    nr = {"x86_64": 314, "aarch64": 274}.get(platform.machine())
    if nr is None or not hasattr(os, "getpriority"):
        return f"time slice not available on {platform.machine() or platform.system()}"
    try:
        libc = ctypes.CDLL(None, use_errno=True)
        tids = [int(t) for t in os.listdir("/proc/self/task")]
        for tid in tids:
            nice = os.getpriority(os.PRIO_PROCESS, tid)
            # struct sched_attr (VER1, 56 bytes): size, policy SCHED_OTHER, flags, nice, priority,
            # runtime = the requested slice, deadline, period, util_min, util_max
            attr = ctypes.create_string_buffer(struct.pack("IIQiIQQQII", 56, 0, 0, nice, 0, ns, 0, 0, 0, 0), 56)
            if libc.syscall(nr, tid, attr, 0) != 0:
                err = ctypes.get_errno()
                return f"time slice not available ({os.strerror(err)})"
    except (OSError, AttributeError) as exc:
        return f"time slice not available ({exc})"
    return f"time slice {ns / 1e6:g} ms on {len(tids)} threads"


def poll(node, subscription) -> None:
    """Leave ``subscription`` of ``node`` out of :class:`FastExecutor`'s wait set: its samples
    stay queued (up to the QoS depth) until :func:`drain` takes them. With another executor the
    subscription is serviced as usual (then :func:`drain` usually finds nothing), so a node that
    polls behaves the same under both, only with more wake-ups under rclpy's."""
    _mark(node, "_polled_subscriptions", subscription)


def defer(node, timer) -> None:
    """Leave ``timer`` of ``node`` out of :class:`FastExecutor`'s wait set: it runs only when the
    node calls :func:`run_deferred`. With another executor the timer runs as usual (and
    :func:`run_deferred` finds it not due)."""
    _mark(node, "_deferred_timers", timer)


def polled(node) -> list:
    """The subscriptions of ``node`` marked with :func:`poll`, in the order they were marked."""
    return getattr(node, "_polled_subscriptions", [])


def deferred(node) -> list:
    """The timers of ``node`` marked with :func:`defer`, in the order they were marked."""
    return getattr(node, "_deferred_timers", [])


def _mark(node, attr: str, entity) -> None:
    """Add ``entity`` once to the node's ordered list ``attr`` (the one record :class:`FastExecutor`
    and the node both read)."""
    marked = getattr(node, attr, None)
    if marked is None:
        marked = []
        setattr(node, attr, marked)
    if entity not in marked:
        marked.append(entity)


def run_deferred(timers, limit: int | None = None) -> int:
    """Call each of ``timers`` that is due (as an executor would: the timer's next call is
    scheduled, then its callback runs), at most ``limit`` of them (None: all), in order; returns
    how many ran."""
    ran = 0
    for tmr in timers:
        if limit is not None and ran >= limit:
            break
        ran += _call_if_due(tmr, tmr.handle)
    return ran


def _call_if_due(timer, handle) -> bool:
    """Call ``timer`` (rclpy Timer, ``handle`` its C handle) if it is due: its next call is
    scheduled, then its callback runs; True if it ran. A timer an earlier callback of the same
    wake-up destroyed (e.g. to replace it with one of another period) is not due."""
    try:
        with handle:
            if not handle.is_timer_ready():
                return False
            handle.call_timer()
    except InvalidHandle:
        return False
    timer.callback()
    return True


def drain(*subscriptions) -> int:
    """Take every queued sample of ``subscriptions`` and call each one's callback, one sample per
    subscription per round in the given order (so two streams published in step, e.g. a pose and
    a tension of the same stamp, keep their interleaving). Returns the number of samples taken."""
    with ExitStack() as stack:
        for sub in subscriptions:
            stack.enter_context(sub.handle)
        return _take_all([_entry(sub) for sub in subscriptions])


def take_newest(subscription) -> bool:
    """Take one sample of a keep-last-1 ``subscription`` (its queue holds at most the newest
    sample) and call its callback; True if there was one. One take instead of :func:`drain`'s
    take-until-empty: each rclpy take costs ~30 us of CPU, an empty one too, which a 1 kHz loop
    pays on its critical path."""
    with subscription.handle:
        h, msg_type, raw, callback, with_info = _entry(subscription)
        info = h.take_message(msg_type, raw)
        if info is None:
            return False
        if with_info:
            callback(info[0], info[1])
        else:
            callback(info[0])
        return True


def _entry(sub) -> tuple:
    """(handle, msg_type, raw, callback, with message info) of an rclpy subscription."""
    from rclpy.subscription import Subscription

    return (sub.handle, sub.msg_type, sub.raw, sub.callback,
            sub._callback_type is Subscription.CallbackType.WithMessageInfo)


def _take_all(entries) -> int:
    """Drain every queue of ``entries`` (:func:`_entry`), one sample per entry per round in the
    given order, each sample straight to its callback; returns the number taken."""
    taken = 0
    while entries:
        still = []
        for entry in entries:
            h, msg_type, raw, callback, with_info = entry
            info = h.take_message(msg_type, raw)
            if info is None:
                continue
            taken += 1
            if with_info:
                callback(info[0], info[1])
            else:
                callback(info[0])
            still.append(entry)
        entries = still
    return taken


def supports(node) -> bool:
    """True if ``node`` has no clients or guard conditions (nothing FastExecutor would miss but
    its QoS event warnings)."""
    return not (list(node.clients) or list(node.guards))


def executor_for(node, fast: bool = True):
    """The executor a node's ``executor_factory`` hook returns: :class:`FastExecutor` when
    ``fast`` and the node :func:`supports` it, else rclpy's SingleThreadedExecutor. (rclpy's C++
    ``EventsExecutor`` was measured against FastExecutor in the three-process 1 kHz loop and lost
    in missed cycles and in every node's CPU per step: docs/benchmarks.md, "Real time".)"""
    from rclpy.executors import SingleThreadedExecutor

    return FastExecutor() if fast and supports(node) else SingleThreadedExecutor()


class FastExecutor:
    """Spin one rclpy node with a prebuilt wait set (see module docstring).

    Args:
        context: the rclpy context (default: the node's, taken in :meth:`add_node`).
    """

    def __init__(self, context=None):
        self._context = context
        self.node = None
        self._key = None
        self._raw_key = None
        self._filtered = None
        self._ws = None
        self._stack = None
        self.taken = 0          # messages handed to callbacks (for statistics)
        self.wakeups = 0        # waits that returned something

    # ------------------------------------------------------------------ setup
    def add_node(self, node) -> bool:
        if self.node is not None and self.node is not node:
            raise ValueError("FastExecutor spins exactly one node")
        self.node = node
        if self._context is None:
            self._context = node.context
        return True

    def _entities(self):
        """(subscriptions, timers, services) of the wait set; rebuilt only when the node's
        entity lists or its polled / deferred sets changed (compared by identity: cheap)."""
        node = self.node
        left_out = polled(node), deferred(node)
        raw = (tuple(node._subscriptions), tuple(node._timers), tuple(node._services), *map(tuple, left_out))
        if raw != self._raw_key:
            self._raw_key = raw
            self._filtered = (tuple(s for s in raw[0] if s not in left_out[0]),
                              tuple(t for t in raw[1] if t not in left_out[1]), raw[2])
        return self._filtered

    def _rebuild(self, subs, timers, services) -> None:
        from rclpy.impl.implementation_singleton import rclpy_implementation as _rclpy

        if self._stack is not None:
            self._stack.close()
        self._stack = ExitStack()
        for ent in subs + timers + services:       # keep the handles alive while they are in the wait set
            self._stack.enter_context(ent.handle)
        self._stack.enter_context(self._context.handle)
        self._ws = _rclpy.WaitSet(len(subs), 0, len(timers), 0, len(services), 0, self._context.handle)
        self._subs = [(s.handle.pointer, _entry(s)) for s in subs]
        self._timers = [(t, t.handle, t.handle.pointer) for t in timers]
        self._services = [(v, v.handle, v.handle.pointer) for v in services]
        self._key = (subs, timers, services)

    # ------------------------------------------------------------------ spinning
    def spin_once(self, timeout_sec: float | None = None) -> None:
        """Wait up to ``timeout_sec`` s (None: forever) for work, then run everything ready."""
        if self.node is None:
            raise RuntimeError("FastExecutor.spin_once before add_node")
        key = self._entities()
        if key != self._key:
            self._rebuild(*key)
        ws = self._ws
        ws.clear_entities()
        for _p, entry in self._subs:
            ws.add_subscription(entry[0])
        for _t, h, _p in self._timers:
            ws.add_timer(h)
        for _v, h, _p in self._services:
            ws.add_service(h)
        timeout_ns = -1 if timeout_sec is None else max(0, int(timeout_sec * 1e9))
        ws.wait(timeout_ns)
        timers_ready = ws.get_ready_entities("timer") if self._timers else ()
        subs_ready = ws.get_ready_entities("subscription") if self._subs else ()
        services_ready = ws.get_ready_entities("service") if self._services else ()
        if not timers_ready and not subs_ready and not services_ready:
            return
        self.wakeups += 1
        # drain every queue, one sample per topic per round
        self.taken += _take_all([e for p, e in self._subs if p in subs_ready])
        for tmr, h, ptr in self._timers:
            if ptr in timers_ready:
                _call_if_due(tmr, h)
        for srv, h, ptr in self._services:
            if ptr in services_ready:
                request, header = h.service_take_request(srv.srv_type.Request)
                if header is not None:
                    srv.send_response(srv.callback(request, srv.srv_type.Response()), header)

    def shutdown(self, timeout_sec: float | None = None) -> bool:
        if self._stack is not None:
            self._stack.close()
            self._stack = None
        self._ws = None
        self._key = self._raw_key = None
        return True
