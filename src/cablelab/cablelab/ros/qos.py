"""QoS profiles of the contract topics (CONTRACT section 2).

* ``/plant_description``: reliable, transient-local, keep-last depth 1 (a late joiner gets it);
* streams (joint states, poses, commands, estimates): reliable, keep-last ``depth``; nodes
  subscribe volatile; publishers are transient-local and keep :data:`PUBLISHER_DEPTH` samples
  (:func:`publisher_qos`): a reliable reader starved by a busy machine (a recorder) catches up
  instead of losing samples (a keep-last writer overwrites what a reader has not acknowledged
  yet), and a transient-local reader that matches a writer late (discovery on a loaded machine
  can finish seconds after the writer's side counted the match) still gets the samples it
  missed;
* recorder subscriptions: reliable keep-all and transient-local, so a briefly busy or late
  recorder delays rather than drops (downgraded to what a third-party publisher offers; what a
  writer dropped anyway is counted by the recorder, see :mod:`cablelab.ros.recorder`).
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
    """:func:`stream_qos` for a publisher: compatible policies with a history deep enough to ride
    out a reliable subscriber (e.g. the recorder) being descheduled for seconds, and
    transient-local so that a transient-local subscriber (the recorder) that matched late gets
    what it missed (volatile subscribers match it too and get only new samples). A subscriber's
    own keep-last depth still bounds what a slow controller sees."""
    qos = stream_qos(depth)
    qos.durability = DurabilityPolicy.TRANSIENT_LOCAL
    return qos


def catch_up_qos(depth: int = PUBLISHER_DEPTH) -> QoSProfile:
    """:func:`stream_qos` for a subscriber that must see every sample, late rather than never
    (estimators: differences, filters and recursive fits over consecutive stamps). Starved for a
    few seconds it works through the backlog instead of losing the oldest samples; controllers
    keep the default depth (a stale state is worth little to them)."""
    return stream_qos(depth)


def recorder_qos(transient_local: bool = True, reliable: bool = True, *,
                 latched: bool = False) -> QoSProfile:
    """Keep-all, reliable unless ``reliable=False`` (to match a best-effort publisher),
    transient-local unless ``transient_local=False`` (to match a volatile publisher);
    keep-last depth 1 when ``latched`` (as /plant_description)."""
    reliability = ReliabilityPolicy.RELIABLE if reliable else ReliabilityPolicy.BEST_EFFORT
    durability = DurabilityPolicy.TRANSIENT_LOCAL if transient_local else DurabilityPolicy.VOLATILE
    if latched:
        return QoSProfile(history=HistoryPolicy.KEEP_LAST, depth=1, reliability=reliability,
                          durability=durability)
    return QoSProfile(history=HistoryPolicy.KEEP_ALL, depth=1000, reliability=reliability,
                      durability=durability)


def qos_for(topic: str, depth: int = 100) -> QoSProfile:
    """The publisher/subscriber QoS of a contract topic."""
    return DESCRIPTION_QOS if topic == "/plant_description" else stream_qos(depth)
