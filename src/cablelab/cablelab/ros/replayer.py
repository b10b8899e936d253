"""The bag replayer node behind ``cablelab replay BAG [--rate R]``.

Republishes every message of a bag on its original topic with its original type (serialised
bytes, no re-encoding), paced by the bag's log times divided by ``rate``. ``/plant_description``
is published first on a transient-local publisher (late joiners still get it). ``/clock``: a bag
that recorded /clock is replayed as recorded; otherwise the node publishes /clock itself (the
log time being replayed, every ``clock_period`` s) so ``use_sim_time`` nodes follow the replay.
A gap in the log times (a forward clock jump, a long pause) is not waited through: it is replayed
as one typical step, with one warning, and the /clock published jumps over it
(:mod:`cablelab.pacing`).
"""
from __future__ import annotations

import heapq
import sys
import time

from rclpy.node import Node

from ..bags import CLOCK_TOPIC, DESCRIPTION_TOPIC, open_bag
from ..pacing import replay_times
from .convert import clock_msg, message_class
from .qos import DESCRIPTION_QOS, publisher_qos


class ReplayNode(Node):
    """Args: bag path, rate (1 = real time), clock_period (s of bag time), start_delay (the
    first message goes out once every publisher has a subscriber, or after start_delay s wall)."""

    def __init__(self, bag_path, rate: float = 1.0, *, clock_period: float = 0.01,
                 start_delay: float = 1.0, topics: list[str] | None = None, quiet: bool = False):
        super().__init__("cablelab_replay")
        bag = open_bag(bag_path)
        if rate <= 0:
            from ..errors import CablelabError

            raise CablelabError(f"replay: --rate must be > 0, got {rate}")
        self.rate = rate
        self.quiet = quiet
        names = [t for t in bag.topics if topics is None or t in topics]
        self.pubs = {}
        for topic in list(names):
            try:
                cls = message_class(bag.topics[topic])
            except ValueError:
                self.get_logger().warning(f"{topic}: message type {bag.topics[topic]} is not "
                                          "installed; not replayed")
                names.remove(topic)
                continue
            qos = DESCRIPTION_QOS if topic == DESCRIPTION_TOPIC else publisher_qos()
            self.pubs[topic] = self.create_publisher(cls, topic, qos)
        if DESCRIPTION_TOPIC in self.pubs and bag.counts[DESCRIPTION_TOPIC]:
            self.pubs[DESCRIPTION_TOPIC].publish(bytes(bag.raw(DESCRIPTION_TOPIC)[1][-1]))
        streams = [t for t in names if t != DESCRIPTION_TOPIC and bag.counts[t]]
        # one merged, time-ordered schedule over all topics (heap merge of per-topic sorted lists)
        per_topic = [[(ns, topic, i) for i, ns in enumerate(bag.raw(topic)[0].tolist())]
                     for topic in streams]
        self.schedule = list(heapq.merge(*per_topic))
        self.raws = {t: bag.raw(t)[1] for t in streams}
        self.t0_bag = self.schedule[0][0] if self.schedule else 0
        # when each message is due (gaps shortened: a clock jump is not slept through)
        due, self.gaps = replay_times([ns for ns, _, _ in self.schedule])
        self.due = due.tolist()
        if self.gaps.count:
            self.get_logger().warning(f"{bag_path}: {self.gaps.warning()}")
        self.own_clock = CLOCK_TOPIC not in bag.topics
        if self.own_clock:
            from rosgraph_msgs.msg import Clock

            self.clock_pub = self.create_publisher(Clock, CLOCK_TOPIC, publisher_qos())
        self.clock_period_ns = int(clock_period * 1e9)
        self.next_clock = self.t0_bag
        self.i = 0
        self.sent_wall: list[float] = []  # monotonic time of each publish (for tests and stats)
        self.done = False
        self.published = 0
        self.start_deadline = time.monotonic() + start_delay
        self.t0_wall = None
        self.timer = self.create_timer(0.001, self.tick)
        self.last_report = time.monotonic()

    def tick(self) -> None:
        now = time.monotonic()
        if self.t0_wall is None:
            connected = all(p.get_subscription_count() > 0 for p in self.pubs.values())
            if not connected and now < self.start_deadline:
                return
            self.t0_wall = now
        horizon = self.t0_bag + int((now - self.t0_wall) * self.rate * 1e9)
        sched, n = self.schedule, len(self.schedule)
        due = self.due
        while self.i < n and due[self.i] <= horizon:
            ns, topic, k = sched[self.i]
            if self.own_clock:
                if ns - self.next_clock > self.gaps.threshold_ns > 0:
                    self.next_clock = ns          # a gap: the clock jumps over it
                while self.next_clock <= ns:
                    self.clock_pub.publish(clock_msg(self.next_clock * 1e-9))
                    self.next_clock += self.clock_period_ns
            self.pubs[topic].publish(bytes(self.raws[topic][k]))
            self.sent_wall.append(time.monotonic())
            self.i += 1
            self.published += 1
        if not self.quiet and now - self.last_report > 5.0:
            self.last_report = now
            left = (due[-1] - horizon) * 1e-9 / self.rate if n else 0.0
            print(f"replay: {self.i}/{n} messages, about {max(left, 0):.0f} s left", file=sys.stderr,
                  flush=True)
        if self.i >= n:
            self.finish()

    def finish(self, timeout: float = 5.0) -> None:
        """Wait (up to ``timeout`` s) until reliable subscribers acknowledged everything, then
        stop: exiting right after the last publish would drop what is still in flight."""
        from rclpy.duration import Duration

        for pub in list(self.pubs.values()) + ([self.clock_pub] if self.own_clock else []):
            pub.wait_for_all_acked(Duration(seconds=timeout))
        self.done = True
        self.exit_code = 0

