"""QoS profiles of the contract topics (CONTRACT section 2).

* ``/plant_description``: reliable, transient-local, keep-last depth 1 (a late joiner gets it);
* streams (joint states, poses, commands, estimates): reliable, volatile, keep-last ``depth``;
  publishers keep :data:`PUBLISHER_DEPTH` samples (:func:`publisher_qos`) so that a reliable
  reader starved by a busy machine (a recorder) catches up instead of losing samples: a
  keep-last writer overwrites what a reader has not acknowledged yet;
* recorder subscriptions: reliable keep-all, so a briefly busy recorder delays rather than drops
  (what a writer dropped anyway is counted by the recorder, see :mod:`cablelab.ros.recorder`).
"""
from __future__ import annotations

from rclpy.qos import DurabilityPolicy, HistoryPolicy, QoSProfile, ReliabilityPolicy

DESCRIPTION_QOS = QoSProfile(history=HistoryPolicy.KEEP_LAST, depth=1,
                             reliability=ReliabilityPolicy.RELIABLE,
                             durability=DurabilityPolicy.TRANSIENT_LOCAL)


def stream_qos(depth: int = 100) -> QoSProfile:
    """Reliable, volatile, keep-last ``depth``: the contract's data streams."""
    return QoSProfile(history=HistoryPolicy.KEEP_LAST, depth=depth,
                      reliability=ReliabilityPolicy.RELIABLE,
                      durability=DurabilityPolicy.VOLATILE)


PUBLISHER_DEPTH = 10000  # samples: 10 s of a 1 kHz stream


def publisher_qos(depth: int = PUBLISHER_DEPTH) -> QoSProfile:
    """:func:`stream_qos` for a publisher: the same (compatible) policies with a history deep
    enough to ride out a reliable subscriber (e.g. the recorder) being descheduled for seconds.
    A subscriber's own keep-last depth still bounds what a slow controller sees."""
    return stream_qos(depth)


def catch_up_qos(depth: int = PUBLISHER_DEPTH) -> QoSProfile:
    """:func:`stream_qos` for a subscriber that must see every sample, late rather than never
    (estimators: differences, filters and recursive fits over consecutive stamps). Starved for a
    few seconds it works through the backlog instead of losing the oldest samples; controllers
    keep the default depth (a stale state is worth little to them)."""
    return stream_qos(depth)


def recorder_qos(transient_local: bool = False, reliable: bool = True) -> QoSProfile:
    """Keep-all, reliable unless ``reliable=False`` (to match a best-effort publisher);
    transient-local depth 1 (as /plant_description) when ``transient_local``."""
    reliability = ReliabilityPolicy.RELIABLE if reliable else ReliabilityPolicy.BEST_EFFORT
    if transient_local:
        return QoSProfile(history=HistoryPolicy.KEEP_LAST, depth=1, reliability=reliability,
                          durability=DurabilityPolicy.TRANSIENT_LOCAL)
    return QoSProfile(history=HistoryPolicy.KEEP_ALL, depth=1000, reliability=reliability,
                      durability=DurabilityPolicy.VOLATILE)
