"""``PlantNode``: what every plant's simulator, estimator and controller node shares.

A plant's node (``plants/<plant>/nodes/<role>.py``) subclasses :class:`PlantNode` and keeps only
its law: the base holds the input monitor (NaN, wrong-length and stale messages are rejected and
counted), the ``/plant_description`` subscription (a bad description is logged and reported, never
raised into the spin loop) or publication, the ``/diagnostics`` status built from the inputs plus
the node's own values, and the choice of executor (``fast_executor``, ``rt_priority``).
"""
from __future__ import annotations

import time
from types import SimpleNamespace

from rclpy.duration import Duration
from rclpy.node import Node
from std_msgs.msg import Float64MultiArray, String

from ..description import load_description
from ..errors import CablelabError
from . import convert
from .diagnostics import Diagnostics
from . import fastspin
from .fastspin import defer, drain, poll, run_deferred, take_newest
from .inputs import InputMonitor
from .lockstep import ADVANCE, FREE, RESEND
from .markers import start_markers
from .qos import DESCRIPTION_QOS, stream_qos
from .rawmsg import RawReader, inertia_arrays, joint_state_arrays, multidof_arrays
from .reference import played_reference
from .status import Latency

PROBE_REPEAT = 5.0  # s wall: the start gate's probe state is published again (see waiting_for_subscribers)
FINISH_ACK_TIMEOUT = 120.0  # s wall: a node that finished waits this long for acknowledgements (drain)
NO_WAIT = Duration(seconds=0)


class PlantNode(Node):
    """Base of every plant node.

    Subclasses call, in ``__init__``: :meth:`declare_params` with their parameter specs (the
    module's ``PARAMETERS``, :mod:`cablelab.ros.params`),
    :meth:`listen_for_description` (estimators, controllers) or :meth:`publish_description`
    (simulators), and :meth:`start_diagnostics` last; they override :meth:`set_description`
    (what the law needs from the description) and :meth:`extend_status` (their own values).
    """

    def __init__(self, name: str, **node_kwargs):
        super().__init__(name, **node_kwargs)
        self.inputs = InputMonitor()
        self.description = None
        self.description_problem = ""
        self.fast = False
        self.keep_first_description = False  # True: later /plant_description messages are ignored
        self._desc_pub = None
        self._raw_readers = {}
        self.latency = Latency()  # per-sample processing time a node measures (latency.since(t0))

    # ------------------------------------------------------------------ parameters
    def declare_params(self, specs) -> SimpleNamespace:
        """Declare the node's ROS parameters from their specs (:class:`~cablelab.ros.params.Param`)
        with descriptors (description, range, read-only) and return the validated values as
        attributes (``v.rate``). Each value (``-p name:=value``, a params file, else the default)
        is checked before use (:meth:`Param.check <cablelab.ros.params.Param.check>`: integers
        accepted where numbers are, range, array length, choices); a bad one raises a one-line
        :class:`~cablelab.errors.CablelabError` naming the node, the parameter, the value and what
        is allowed. Parameters already declared keep their value."""
        overrides = getattr(self, "_parameter_overrides", {})   # rclpy: -p and --params-file values
        values = {}
        for spec in specs:
            if self.has_parameter(spec.name):
                values[spec.name] = self.get_parameter(spec.name).value
                continue
            raw = overrides[spec.name].value if spec.name in overrides else spec.default
            value = spec.check(raw, f"{self.get_name()}")
            # declared with the checked value itself (an int given for a double parameter is
            # declared as the double it means, not refused by rclpy's type check)
            self.declare_parameter(spec.name, value, spec.descriptor(), ignore_override=True)
            values[spec.name] = value
        return SimpleNamespace(**values)

    def unknown_parameters(self) -> list[str]:
        """Overridden parameter names this node never declared (typos: ``-p rat:=100``)."""
        overrides = getattr(self, "_parameter_overrides", {})
        return sorted(n for n in overrides if not self.has_parameter(n))

    def param(self, name: str, default):
        """A ROS parameter declared (once) from its default alone (type inferred, validated like
        :meth:`declare_params`); prefer a :class:`~cablelab.ros.params.Param` spec."""
        from .params import Param

        if self.has_parameter(name):
            return self.get_parameter(name).value
        return getattr(self.declare_params((Param(name, default, "", read_only=False),)), name)

    def choice(self, name: str, default: str, allowed: tuple[str, ...]) -> str:
        """A text ROS parameter restricted to ``allowed`` (one-line error naming it otherwise)."""
        from .params import Param

        return getattr(self.declare_params((Param(name, default, "", choices=tuple(allowed)),)), name)

    def use_fast_executor(self, default: bool = True) -> None:
        """Parameters ``fast_executor`` (spin with :class:`~cablelab.ros.fastspin.FastExecutor`),
        ``rt_priority`` (SCHED_FIFO priority, 0 = off; needs the privilege), and the placement a
        deployment gives a 1 kHz loop without privileges: ``cpu_affinity`` (CPU numbers the
        node's threads run on, [-1] = any), ``niceness`` (0-19: lower priority for a node off
        the critical path), ``sched_idle`` (run in the SCHED_IDLE class: only on otherwise idle
        CPU, preempted at once, :func:`~cablelab.ros.fastspin.set_idle_class`) and ``sched_slice``
        (s, 0 = the kernel's default: a short EEVDF time slice for a node on the critical path,
        :func:`~cablelab.ros.fastspin.set_latency_slice`); ``python_idle`` is kept for
        :func:`~cablelab.ros.fastspin.yield_to_compiled`. Their specs:
        :func:`~cablelab.ros.params.executor_params`."""
        from .fastspin import (set_background, set_cpu_affinity, set_idle_class, set_latency_slice,
                               set_realtime_priority)
        from .params import executor_params

        v = self.declare_params(executor_params(default))
        self.fast = bool(v.fast_executor)
        self.python_idle = bool(v.python_idle)      # (read by a node that starts a compiled path)
        cpus = [int(c) for c in v.cpu_affinity if int(c) >= 0]
        if cpus:
            self.get_logger().info(f"cpu_affinity: {set_cpu_affinity(cpus)}")
        nice = int(v.niceness)
        if nice > 0:
            self.get_logger().info(f"niceness: {set_background(nice)}")
        if bool(v.sched_idle):
            self.get_logger().info(f"sched_idle: {set_idle_class()}")
        slice_s = float(v.sched_slice)
        if slice_s > 0:
            self.get_logger().info(f"sched_slice: {set_latency_slice(slice_s)}")
        rt = int(v.rt_priority)
        if rt > 0:
            self.get_logger().info(f"rt_priority: {set_realtime_priority(rt)}")

    def executor_factory(self):
        """The executor :func:`cablelab.ros.runner.run_node` spins this node with."""
        from .fastspin import executor_for

        return executor_for(self, self.fast)

    # ------------------------------------------------------------------ inputs
    def accept(self, name: str, values) -> bool:
        """:meth:`InputMonitor.accept <cablelab.ros.inputs.InputMonitor.accept>` at the present
        wall time: True if ``values`` of input ``name`` are usable (else counted as rejected)."""
        return self.inputs.accept(name, values, time.monotonic())

    def decode(self, name: str, decode, msg):
        """``decode(msg)`` (e.g. :func:`~cablelab.ros.rawmsg.joint_state_arrays` of raw bytes), or
        None with the message counted as rejected on input ``name`` when it is not one
        (``ValueError``)."""
        try:
            return decode(msg)
        except ValueError:
            self.accept(name, None)
            return None

    def take_command(self, name: str, msg, lock=None):
        """The values of a ``Float64MultiArray`` command on input ``name`` when usable (checked by
        the input monitor) and, with a :class:`~cablelab.ros.lockstep.LockStep`, answering the
        last published state (an answer to an earlier one is counted and ignored); else None."""
        values = convert.float_array(msg)
        if not self.accept(name, values) or (lock is not None and not lock.offer(convert.command_stamp(msg))):
            return None
        return values

    def subscribe(self, kind, topic: str, callback, qos, raw: bool = False, polled: bool = False):
        """``create_subscription``; ``polled``: left out of the fast executor's wait set
        (:func:`~cablelab.ros.fastspin.poll`), its samples wait queued until :meth:`take_polled`
        (it joins :attr:`polled`, in subscription order)."""
        sub = self.create_subscription(kind, topic, callback, qos, raw=raw)
        if polled:
            poll(self, sub)
        return sub

    @property
    def polled(self) -> list:
        """The subscriptions left out of the fast executor's wait set (``subscribe(polled=True)``),
        in subscription order; assigning a list replaces them (``[]``: none, e.g. a test that
        calls the callbacks by hand)."""
        return fastspin.polled(self)

    @polled.setter
    def polled(self, subscriptions) -> None:
        self._polled_subscriptions = list(subscriptions)

    @property
    def deferred(self) -> list:
        """The timers left out of the fast executor's wait set (:meth:`defer_timers`), in order."""
        return fastspin.deferred(self)

    def take_polled(self, newest: bool = False) -> int:
        """Run the callbacks of every sample queued on the :attr:`polled` subscriptions, in order
        (:func:`~cablelab.ros.fastspin.drain`), or with ``newest`` one take from each (keep-last-1
        queues hold only the newest: :func:`~cablelab.ros.fastspin.take_newest`); returns how many."""
        if newest:
            return sum(take_newest(sub) for sub in self.polled)
        return drain(*self.polled)

    def defer_timers(self, timers) -> None:
        """Leave ``timers`` (e.g. the /diagnostics and 3D-view timers) out of the fast
        executor's wait set (:func:`~cablelab.ros.fastspin.defer`): they run when the node calls
        :meth:`run_deferred`, at a point where they cannot delay its deadline work."""
        for tmr in timers:
            defer(self, tmr)

    def run_deferred(self, limit: int | None = 1) -> int:
        """Run the due :attr:`deferred` timers, at most ``limit`` (None: all) per call, the rest
        on the next call (:func:`~cablelab.ros.fastspin.run_deferred`); returns how many ran."""
        return run_deferred(self.deferred, limit) if self.deferred else 0

    def decode_raw(self, name: str, kind, msg):
        """The arrays of a ``kind`` message (``JointState``:
        :func:`~cablelab.ros.rawmsg.joint_state_arrays`, ``MultiDOFJointTrajectory``:
        :func:`~cablelab.ros.rawmsg.multidof_arrays`, ``InertiaStamped``:
        :func:`~cablelab.ros.rawmsg.inertia_arrays`) given as an object or as its serialised
        bytes (a subscription with ``raw=True``), read with one reader per type; None, counted as
        rejected on input ``name``, when the bytes are not one."""
        reader = self._raw_readers.get(kind)
        if reader is None:
            reader = self._raw_readers[kind] = RawReader(kind)
        arrays = {"MultiDOFJointTrajectory": multidof_arrays,
                  "InertiaStamped": inertia_arrays}.get(kind.__name__, joint_state_arrays)
        return self.decode(name, lambda m: arrays(m, reader), msg)

    def play_reference(self, bag: str, topic: str, joints, builtin=None, platform: bool = False):
        """:func:`~cablelab.ros.reference.played_reference` of this node: the reference it
        plays itself from ``bag`` or ``builtin``, None when it follows the topic."""
        return played_reference(self, bag, topic, joints, builtin, platform)

    # ------------------------------------------------------------------ description
    def listen_for_description(self, text: str = "", keep_first: bool = False) -> None:
        """Subscribe to ``/plant_description`` (transient local); ``text`` (a ``description``
        parameter) is used at once when given. ``keep_first``: the first valid description
        configures the node for good (:attr:`keep_first_description`)."""
        self.keep_first_description = self.keep_first_description or keep_first
        self.create_subscription(String, "/plant_description", self.on_description, DESCRIPTION_QOS)
        if text:
            self.set_description(load_description(text))

    def on_description(self, msg: String) -> None:
        """/plant_description callback: parse, then :meth:`set_description` (errors logged)."""
        if self.keep_first_description and self.description is not None:
            return
        try:
            desc = load_description(msg.data)
        except CablelabError as exc:
            self.description_problem = " ".join(f"bad /plant_description: {exc}".split())
            self.get_logger().error(f"/plant_description: {exc}")
            return
        self.set_description(desc)

    def set_description(self, desc) -> None:
        """Take a validated description (override to configure the law; call super)."""
        self.description = desc

    def publish_description(self, desc) -> None:
        """Publish ``desc`` on ``/plant_description`` (transient local: late joiners get it).
        The publisher owns the description: it never takes another one from the topic."""
        self.description = desc
        self.keep_first_description = True
        self._desc_pub = self.create_publisher(String, "/plant_description", DESCRIPTION_QOS)
        self._desc_pub.publish(convert.string_msg(desc.to_yaml()))

    # ------------------------------------------------------------------ simulators: start gate
    def start_gate(self) -> None:
        """Parameter ``wait_for_subscribers`` (simulators): before time starts, wait (at most
        60 s) until the state topic has that many subscribers, see :meth:`waiting_for_subscribers`."""
        from .params import START_GATE

        self.wait_subs = int(self.declare_params(START_GATE).wait_for_subscribers)
        self.probe_sent: float | None = None
        self.created = time.monotonic()

    def waiting_for_subscribers(self, publisher, last_publish: float, republish,
                                every: float = 0.5) -> bool:
        """True while time must not start yet (for at most 60 s): fewer than
        ``wait_for_subscribers`` subscribers of ``publisher`` (meanwhile ``republish()`` the
        initial state every ``every`` s wall after ``last_publish``, for late joiners), or a
        reliable subscriber has not yet acknowledged the initial state published once more when
        the count was reached.

        The count is the writer's side of the match; the subscriber may match the writer much
        later (seconds on a loaded machine) and drops every sample until then. A subscriber that
        acknowledged a sample published after the count was reached has matched, so from the
        first step on a recorder gets every sample. (Samples published before the writer matched
        a volatile subscriber count as acknowledged, hence the one more; while waiting for the
        acknowledgements nothing is published, since they come with the writer's periodic
        heartbeat, every few seconds, and every new sample would need another one; the probe is
        repeated every :data:`PROBE_REPEAT` s in case it was lost.)"""
        if not self.wait_subs:
            return False
        now = time.monotonic()
        if now - self.created >= 60.0:
            self.get_logger().warning(f"time starts without all {self.wait_subs} subscribers "
                                      "matched and acknowledged after 60 s")
            self.wait_subs = 0
            return False
        if publisher.get_subscription_count() < self.wait_subs:
            self.probe_sent = None
            if now - last_publish > every:
                republish()
            return True
        if self.probe_sent is None or now - self.probe_sent > PROBE_REPEAT:
            republish()
            self.probe_sent = now
            return True
        if self.all_acknowledged():
            self.get_logger().info(f"time starts: {self.wait_subs} subscribers matched and "
                                   f"acknowledged after {now - self.created:.1f} s")
            self.wait_subs = 0
            return False
        return True

    def command_input(self, topic: str, length: int, timeout: float, qos=None, raw: bool = False,
                      polled: bool = False, required: bool = True):
        """A simulator's commands: input ``effort_commands`` (``length`` values, stale after
        ``timeout`` s wall; ``required`` as :meth:`InputMonitor.add
        <cablelab.ros.inputs.InputMonitor.add>`) and its std_msgs/Float64MultiArray subscription
        on ``topic`` calling ``self.on_command`` (:meth:`subscribe`; ``qos`` default: a stream's)."""
        self.inputs.add("effort_commands", timeout=timeout, length=length, required=required)
        return self.subscribe(Float64MultiArray, topic, self.on_command, qos or stream_qos(), raw, polled)

    def start_stepping(self, period: float, markers_topic: str, frame, stamp, markers_rate: float,
                       publish_first: bool = True) -> None:
        """A simulator's last call in ``__init__``: /diagnostics (:meth:`start_diagnostics`), the
        timer calling ``self.tick`` every ``period`` s wall (:attr:`timer`), the 3D view ``frame()``
        on ``markers_topic`` stamped ``stamp()`` at ``markers_rate`` Hz wall
        (:func:`~cablelab.ros.markers.start_markers`), and, with ``publish_first``, the initial
        state (``self.publish_state()``)."""
        self.start_diagnostics()
        self.timer = self.create_timer(period, self.tick)
        start_markers(self, markers_topic, frame, stamp, markers_rate)
        if publish_first:
            self.publish_state()

    def may_step(self, lock, publisher, republish, every: float = 0.5) -> str | None:
        """A simulator's timer: the start gate (:meth:`waiting_for_subscribers` on ``publisher``),
        then the lock-step ``lock``: its ADVANCE (the answer to the last state is here) or FREE
        (real-time rules) when the simulation steps now, None while it waits (on RESEND the last
        state is published again with ``republish()``: the controller may have missed it)."""
        if self.waiting_for_subscribers(publisher, lock.published_at, republish, every):
            return None
        step = lock.poll(time.monotonic())
        if step == RESEND:
            republish()
        return step if step in (ADVANCE, FREE) else None

    def all_acknowledged(self) -> bool:
        """Whether every matched reliable subscriber acknowledged every sample this node
        published (checked without waiting; /diagnostics, published on a timer, not counted)."""
        diag = getattr(getattr(self, "diag", None), "pub", None)
        return all(pub.wait_for_all_acked(NO_WAIT) for pub in self.publishers if pub is not diag)

    def drain(self, executor, timeout: float = FINISH_ACK_TIMEOUT) -> None:
        """Called by the runner after the spin loop. A node that finished by itself (``done``,
        e.g. a simulator at its ``duration``) waits, up to ``timeout`` s, until every reliable
        subscriber acknowledged every sample it published: its writers' history, which a
        recorder that fell behind still needs, ends with the process. (Stopped by a signal it
        exits at once.)"""
        if not getattr(self, "done", False):
            return
        t_end = time.monotonic() + timeout
        diag = getattr(getattr(self, "diag", None), "pub", None)
        late = []
        for pub in self.publishers:
            left = max(0.0, t_end - time.monotonic())
            if pub is not diag and not pub.wait_for_all_acked(Duration(seconds=left)):
                late.append(pub.topic_name)
        if late:
            self.get_logger().warning(f"exiting with samples not acknowledged after {timeout:g} s "
                                      f"on {', '.join(late)}")

    # ------------------------------------------------------------------ diagnostics
    def start_diagnostics(self) -> None:
        """Publish :meth:`status` on /diagnostics (call last in ``__init__``)."""
        self.diag = Diagnostics(self, update=self.status)

    def status(self):
        """``(level, message, values)``: the inputs' status, extended by the node, and the p99
        of the per-sample processing time when the node measures it (:attr:`latency`)."""
        level, msg, values = self.inputs.status(time.monotonic())
        if self.description_problem:
            level = max(level, 1)
            msg = self.description_problem if msg == "ok" else f"{msg}; {self.description_problem}"
        level, msg, values = self.extend_status(level, msg, values)
        return level, msg, self.latency.report(values)     # (nothing before the first sample)

    def extend_status(self, level: int, msg: str, values: dict):
        """Add the node's own values / raise the level (override)."""
        return level, msg, values


__all__ = ["PlantNode"]
