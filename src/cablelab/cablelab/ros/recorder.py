"""The bag recorder node behind ``cablelab record``.

Subscribes to a topic set with serialised (raw) callbacks and matching QoS (reliable,
transient-local: depth 1 for /plant_description, keep-all for streams, so that a recorder whose
side of a match completes late still gets the samples it missed; downgraded to what a publisher
offers), writes every message as received into a
rosbag2 MCAP bag (log time = receive time, wall clock ns) and flushes a complete MCAP chunk to
disk every ``flush_period`` s. Topics whose type is not known in advance (``--topics``) are
subscribed as soon as they appear in the ROS graph.

Draining: the node spins with :class:`~cablelab.ros.fastspin.FastExecutor` (one wait set, every
queued sample taken in one wake-up, straight to the write), cheaper per message than
rclpy's executor, so that a recorder sharing a busy CPU with the nodes it records keeps up with
them; the publishers keep seconds of history (:func:`~cablelab.ros.qos.publisher_qos`) for the
moments it does not.

Lost samples: counted per topic as the larger of the DDS message-lost status of the subscription
(samples the writer dropped before this reader had them) and the gaps in the publication
sequence numbers (while the topic has one publisher). A loss is reported on ``/diagnostics``
(WARN naming topic and count) and written into the bag's metadata.yaml ``custom_data`` as
``cablelab.lost.<topic>: <count>`` (every recorded topic, 0 included), which ``cablelab info``
shows.

Shutdown (SIGINT/SIGTERM, ``--duration`` elapsed): the bag is closed: MCAP summary + footer and
metadata.yaml written. SIGKILL: nothing can run; the .mcap holds every chunk flushed so far
(at most ``flush_period`` s is lost), without footer and without metadata.yaml; ``open_bag(...,
recover=True)`` / ``cablelab info --recover`` read that complete part (see docs/bags.md).
"""
from __future__ import annotations

import sys
import time

from rclpy.node import Node

from ..bags import BagWriter
from ..errors import CablelabError
from .convert import message_class
from ..bags.reader import LOST_KEY  # metadata.yaml custom_data key prefix: samples lost per topic
from .qos import recorder_qos


class RecorderNode(Node):
    """Args: output bag path, topics (name -> type or None to discover), overwrite, duration
    (s, 0 = until stopped), flush_period (s), fast (spin with FastExecutor; False: rclpy's
    executor, for comparisons)."""

    def __init__(self, output, topics: dict[str, str | None], *, overwrite: bool = False,
                 duration: float = 0.0, flush_period: float = 1.0, quiet: bool = False,
                 fast: bool = True):
        super().__init__("cablelab_recorder")
        writer = output if isinstance(output, BagWriter) else BagWriter(output, overwrite=overwrite)
        self.writer = writer.open()
        from ..cdr import typestore

        typestore()  # build the message definitions now, not in the first callback
        self.wanted = dict(topics)
        self.subs = {}
        self.sub_qos: dict[str, tuple[bool, bool]] = {}  # topic -> (reliable, transient_local)
        self.registered: set[str] = set()
        self.counts = {t: 0 for t in topics}
        self.lost_events: dict[str, int] = {}    # topic -> DDS message-lost total (all subscriptions)
        self.lost_gaps: dict[str, int] = {}      # topic -> samples missing between sequence numbers
        self.single_writer: set[str] = set()     # topics with exactly one publisher (gaps mean loss)
        self._lost_handles: dict[str, tuple] = {}  # topic -> (event handle, total before it)
        self._last_seq: dict[str, int] = {}      # topic -> last publication sequence number
        self.quiet = quiet
        self.fast = bool(fast)
        self.duration = float(duration)
        self.t_start = time.monotonic()
        self.done = False
        self.closed = False
        self.failed: str | None = None
        for topic, msgtype in self.wanted.items():
            if msgtype:
                self._subscribe(topic, msgtype)
        self.mismatch_reported = set()
        self.create_timer(0.2, self._discover)
        self.create_timer(flush_period, self._flush)
        if self.duration > 0:
            self.create_timer(0.05, self._check_duration)
        self.create_timer(5.0, self._progress)
        from .diagnostics import Diagnostics

        self.diag = Diagnostics(self, update=self.status)

    def executor_factory(self):
        """Spin with :class:`~cablelab.ros.fastspin.FastExecutor`: batch takes, no per-message
        executor overhead (the recorder must keep up with 1 kHz topics on a busy machine)."""
        from .fastspin import executor_for

        return executor_for(self, self.fast)

    def _subscribe(self, topic: str, msgtype: str, reliable: bool = True,
                   transient: bool | None = None) -> None:
        try:
            cls = message_class(msgtype)
        except ValueError:
            raise CablelabError(f"record: topic {topic}: unknown message type {msgtype}") from None
        write = self.writer.write_raw
        counts = self.counts
        if transient is None:
            transient = True        # downgraded by _adapt_qos for a volatile publisher
        registered = self.registered
        gaps = self.lost_gaps
        gaps.setdefault(topic, 0)
        single = self.single_writer
        last_seq = self._last_seq
        last_seq.pop(topic, None)
        now_ns = time.time_ns

        def callback(data: bytes, info: dict) -> None:
            try:
                if topic not in registered:
                    self.writer.add_topic(topic, msgtype, transient_local=topic == "/plant_description")
                    registered.add(topic)
                write(topic, now_ns(), data)
            except OSError as exc:
                self._write_failed(exc)
            counts[topic] += 1
            seq = info.get("publication_sequence_number")
            if seq is not None:
                prev = last_seq.get(topic)
                if prev is not None and seq > prev + 1 and topic in single:
                    gaps[topic] += seq - prev - 1
                last_seq[topic] = seq

        qos = recorder_qos(transient, reliable, latched=topic == "/plant_description")
        sub = self.create_subscription(cls, topic, callback, qos, raw=True)
        self.subs[topic] = sub
        self.sub_qos[topic] = (reliable, transient)
        self._lost_handles[topic] = (_lost_event(sub), self.lost_events.get(topic, 0))

    def _adapt_qos(self, topic: str, msgtype: str) -> None:
        """Downgrade a subscription to what every publisher offers (like rosbag2): best-effort if a
        publisher is best-effort, volatile if one is volatile (else they would never match)."""
        from rclpy.qos import DurabilityPolicy, ReliabilityPolicy

        infos = self.get_publishers_info_by_topic(topic)
        if not infos:
            return
        reliable, transient = self.sub_qos[topic]
        if reliable and any(i.qos_profile.reliability == ReliabilityPolicy.BEST_EFFORT for i in infos):
            reliable = False
        if transient and any(i.qos_profile.durability == DurabilityPolicy.VOLATILE for i in infos):
            transient = False
        if (reliable, transient) != self.sub_qos[topic]:
            # a volatile stream is normal (a third-party driver, the simulators' keep-last-1 3D
            # view: the recorder only asks for transient-local to get what it missed by matching
            # late); anything else is less than the contract asks
            log = (self.get_logger().debug if reliable and topic != "/plant_description"
                   else self.get_logger().warning)
            log(f"{topic}: a publisher offers {'best-effort' if not reliable else 'volatile'} "
                "QoS; recording it with that QoS")
            self._retire_lost_handle(topic)
            self.destroy_subscription(self.subs.pop(topic))
            self._subscribe(topic, msgtype, reliable, transient)

    def _discover(self) -> None:
        types = dict(self.get_topic_names_and_types())
        for topic, msgtype in self.wanted.items():
            if topic not in types:
                continue
            found = [t for t in types[topic] if msgtype is None or t == msgtype]
            others = [t for t in types[topic] if msgtype is not None and t != msgtype]
            if others and topic not in self.mismatch_reported:
                self.mismatch_reported.add(topic)
                self.get_logger().error(f"topic {topic} is published with type {others[0]}, "
                                        f"expected {msgtype}: those messages are not recorded")
            if topic not in self.subs and found:
                self._subscribe(topic, found[0])
            if topic in self.subs and found:
                self._adapt_qos(topic, found[0])
                single = self.count_publishers(topic) == 1
                if single != (topic in self.single_writer):
                    self._last_seq.pop(topic, None)     # (sequence numbers are per writer)
                    (self.single_writer.add if single else self.single_writer.discard)(topic)
        self._poll_lost()

    # ------------------------------------------------------------------ lost samples
    def _retire_lost_handle(self, topic: str) -> None:
        """Keep the message-lost total of a subscription about to be destroyed, and release its
        status handle (it holds the subscription)."""
        if topic in self._lost_handles:
            self._poll_lost()
            handle, _ = self._lost_handles.pop(topic)
            if handle is not None:
                handle.destroy_when_not_in_use()

    def _poll_lost(self) -> None:
        """Read the DDS message-lost status of every subscription (non-blocking)."""
        for topic, (handle, before) in self._lost_handles.items():
            if handle is None:
                continue
            try:
                with handle:
                    total = int(handle.take_event().total_count)
            except Exception:  # noqa: BLE001 - the status is a report, never a reason to stop
                continue
            self.lost_events[topic] = before + total

    def lost(self) -> dict[str, int]:
        """Samples lost per topic (only topics that lost any)."""
        self._poll_lost()
        out = {}
        for topic in self.wanted:
            n = max(self.lost_events.get(topic, 0), self.lost_gaps.get(topic, 0))
            if n:
                out[topic] = n
        return out

    def status(self):
        """/diagnostics: OK with the message counts, WARN naming every topic that lost samples."""
        lost = self.lost()
        values = {f"recorded {t}": str(n) for t, n in self.counts.items() if n}
        values.update({f"lost {t}": str(n) for t, n in lost.items()})
        if self.failed:
            return 2, self.failed, values
        if lost:
            return 1, "lost samples: " + ", ".join(f"{t} {n}" for t, n in lost.items()), values
        return 0, "ok", values

    def drain(self, executor, quiet_time: float = 0.2, limit: float = 1.0) -> None:
        """After a stop request: keep taking messages DDS already delivered until none arrived
        for ``quiet_time`` s (at most ``limit`` s), so a stop loses nothing that was received."""
        t_end = time.monotonic() + limit
        last_total, last_change = -1, time.monotonic()
        while time.monotonic() < t_end:
            executor.spin_once(timeout_sec=0.05)
            total = sum(self.counts.values())
            if total != last_total:
                last_total, last_change = total, time.monotonic()
            elif time.monotonic() - last_change > quiet_time:
                break

    def _flush(self) -> None:
        if not self.closed and self.failed is None:
            try:
                self.writer.flush()
            except OSError as exc:
                self._write_failed(exc)

    def _write_failed(self, exc: OSError) -> None:
        """Disk full / read-only / I/O error while recording: stop with one line (the run loop
        prints it, exit 2); the chunks flushed so far stay readable (--recover, cablelab repair)."""
        from ..atomic import os_error_message

        self.failed = os_error_message(self.writer.path, exc).replace(
            "; nothing was written", "; the part flushed before is kept: read it with --recover or "
                                     "rewrite it with cablelab repair")
        self.closed = True          # no footer can be written: leave the flushed chunks as they are
        raise CablelabError(self.failed)

    def _check_duration(self) -> None:
        if time.monotonic() - self.t_start >= self.duration:
            self.done = True

    def _progress(self) -> None:
        if self.quiet:
            return
        elapsed = time.monotonic() - self.t_start
        total = sum(self.counts.values())
        eta = f", {max(0.0, self.duration - elapsed):.0f} s left" if self.duration > 0 else ""
        print(f"record: {elapsed:.0f} s, {total} messages on {sum(1 for c in self.counts.values() if c)}"
              f"/{len(self.counts)} topics{eta}", file=sys.stderr, flush=True)

    def shutdown(self) -> None:
        """Close the bag (MCAP footer + metadata.yaml with the lost-sample counts)."""
        if not self.closed:
            self.closed = True
            lost = self.lost()
            for topic in list(self._lost_handles):
                self._retire_lost_handle(topic)
            for topic in sorted(set(self.registered) | set(lost)):
                self.writer.set_custom_data(LOST_KEY + topic, str(lost.get(topic, 0)))
            self.writer.close()
            if not self.quiet:
                print(f"record: wrote {sum(self.counts.values())} messages to {self.writer.path}",
                      file=sys.stderr, flush=True)
            if lost:
                print("record: warning: lost samples: " + ", ".join(f"{t} {n}" for t, n in lost.items()),
                      file=sys.stderr, flush=True)


def _lost_event(sub):
    """The DDS message-lost status handle of an rclpy subscription (None where the middleware
    has none): polled with ``take_event()``, which returns the running total."""
    from rclpy.event_handler import QoSSubscriptionEventType, UnsupportedEventTypeError
    from rclpy.impl.implementation_singleton import rclpy_implementation as _rclpy

    try:
        with sub.handle:
            return _rclpy.EventHandle(sub.handle, QoSSubscriptionEventType.RCL_SUBSCRIPTION_MESSAGE_LOST)
    except (UnsupportedEventTypeError, RuntimeError):
        return None
