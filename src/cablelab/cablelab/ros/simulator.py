"""What every simulator node wires the same way: /clock, /plant_description, /diagnostics, the
stepping timer, the 3D view and the first state (:func:`start_simulation`), and its state
publishers (:func:`state_publishers`). A simulator node then holds only its plant's parts::

    self.pub_js, self.pub_truth = state_publishers(self, (JointState, topics.JOINT_STATES),
                                                   (JointState, topics.GROUND_TRUTH))
    ...
    start_simulation(self, desc, 1.0 / v.rate, topics.MARKERS, frame, stamp, v.markers_rate)

The node provides ``tick()`` (called every period) and ``publish_state()``.
"""
from __future__ import annotations

from .clock import ClockPublisher
from .markers import start_markers
from .qos import publisher_qos

__all__ = ["start_simulation", "state_publishers"]


def state_publishers(node, *kinds_topics) -> list:
    """A publisher (the state QoS, :func:`~cablelab.ros.qos.publisher_qos`) per ``(message
    type, topic)``, in order; None for a ``(type, None)`` pair (a topic switched off)."""
    return [None if topic is None else node.create_publisher(kind, topic, publisher_qos())
            for kind, topic in kinds_topics]


def start_simulation(node, desc, period: float, markers_topic: str, frame, stamp, markers_rate: float,
                     publish_first: bool = True) -> None:
    """A simulator's last call in ``__init__``: ``node.clock`` (/clock), ``desc`` published on
    /plant_description (:meth:`PlantNode.publish_description
    <cablelab.ros.plant_node.PlantNode.publish_description>`), /diagnostics, ``node.timer``
    calling ``node.tick()`` every ``period`` s wall, the 3D view ``frame()`` on
    ``markers_topic`` stamped ``stamp()`` at ``markers_rate`` Hz wall
    (:func:`~cablelab.ros.markers.start_markers`) and, with ``publish_first``, the initial state
    (``node.publish_state()``)."""
    node.clock = ClockPublisher(node)
    node.publish_description(desc)
    node.start_diagnostics()
    node.timer = node.create_timer(period, node.tick)
    start_markers(node, markers_topic, frame, stamp, markers_rate)
    if publish_first:
        node.publish_state()
