"""/clock publisher for simulators: sim time out, optionally throttled to ``period`` s of sim time."""
from __future__ import annotations

from rosgraph_msgs.msg import Clock

from .convert import clock_msg
from .qos import publisher_qos


class ClockPublisher:
    """Publishes rosgraph_msgs/Clock on /clock.

    Args:
        node: the rclpy node
        period: minimum sim-time step between two published clocks, s (0: publish every call)
    """

    def __init__(self, node, period: float = 0.0):
        self.pub = node.create_publisher(Clock, "/clock", publisher_qos())
        self.period = float(period)
        self.last = None

    def publish(self, t: float) -> bool:
        """Publish sim time t (s) unless less than ``period`` after the last one; True if sent.
        Time never goes backwards: an earlier t is ignored."""
        if self.last is not None and (t < self.last or t - self.last < self.period - 1e-12):
            return False
        self.pub.publish(clock_msg(t))
        self.last = t
        return True
