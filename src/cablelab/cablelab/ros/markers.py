"""The 3D view of a simulator node: ``start_markers(node, topic, frame, rate)`` publishes
``frame()`` (a list of :class:`cablelab.markers.Marker`) as visualization_msgs/MarkerArray on
its own wall-clock timer, pre-encoded (:class:`cablelab.markers.MarkerEncoder`), stamped with
``stamp()`` (the node's sim time): off the state -> command path."""
from __future__ import annotations

from visualization_msgs.msg import MarkerArray

from ..markers import MarkerEncoder
from .qos import stream_qos


def start_markers(node, topic: str, frame, stamp, rate: float):
    """Publish ``frame()`` at ``rate`` Hz of wall time (0 or less: nothing). Returns the
    publisher or None."""
    if not rate > 0:
        return None
    enc = MarkerEncoder(frame())
    pub = node.create_publisher(MarkerArray, topic, stream_qos(1))
    node.create_timer(1.0 / rate, lambda: pub.publish(enc.encode([stamp()], [frame()])[0]))
    return pub
