"""/diagnostics publisher: one DiagnosticStatus per node, OK/WARN/ERROR with key values."""
from __future__ import annotations

from diagnostic_msgs.msg import DiagnosticArray, DiagnosticStatus, KeyValue

from .qos import stream_qos

LEVELS = {0: DiagnosticStatus.OK, 1: DiagnosticStatus.WARN, 2: DiagnosticStatus.ERROR}


class Diagnostics:
    """Publishes the node's status on /diagnostics every ``period`` s and on every level change.

    Args:
        node: the rclpy node
        name: status name (default: node name)
        update: optional callable ``() -> (level, message, {key: value})`` polled at each period
    """

    def __init__(self, node, name: str | None = None, period: float = 1.0, update=None):
        self.node = node
        self.name = name or node.get_name()
        self.update = update
        self.level, self.message, self.values = 0, "starting", {}
        self.pub = node.create_publisher(DiagnosticArray, "/diagnostics", stream_qos(10))
        self.timer = node.create_timer(period, self.publish)

    def set(self, level: int, message: str, values: dict | None = None) -> None:
        """Set the status (0 OK, 1 WARN, 2 ERROR); publishes at once if the level changed."""
        changed = level != self.level
        self.level, self.message = level, message
        if values is not None:
            self.values = dict(values)
        if changed:
            self.publish(poll=False)

    def publish(self, poll: bool = True) -> None:
        if poll and self.update is not None:
            level, message, values = self.update()
            self.level, self.message, self.values = level, message, dict(values)
        arr = DiagnosticArray()
        arr.header.stamp = self.node.get_clock().now().to_msg()
        st = DiagnosticStatus()
        st.level = LEVELS.get(self.level, DiagnosticStatus.ERROR)
        st.name = self.name
        st.message = self.message
        st.hardware_id = self.node.get_fully_qualified_name()
        st.values = [KeyValue(key=str(k), value=str(v)) for k, v in self.values.items()]
        arr.status = [st]
        self.pub.publish(arr)
