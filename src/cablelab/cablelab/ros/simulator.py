"""The base of every simulator node: what they all wire and step the same way.

A simulator node subclasses :class:`SimulatorNode`, builds its plant, creates its state
publishers (:meth:`~SimulatorNode.state_publishers`) and its command input, and calls
:meth:`~SimulatorNode.start_simulation` last; it provides :meth:`~SimulatorNode.step` (one period of
physics) and :meth:`~SimulatorNode.publish_state`. The base steps it on a timer, through the start
gate and, with a ``lock`` (:class:`~cablelab.ros.lockstep.LockStep`), in lock-step with the
controller, stops it at ``duration`` and reports its sim time on /diagnostics::

    class AxisSimNode(SimulatorNode):
        def __init__(self):
            ...
            self.pub_js, self.pub_truth = self.state_publishers((JointState, topics.JOINT_STATES), ...)
            self.start_simulation(desc, 1.0 / v.rate, topics.MARKERS, frame, v.markers_rate)

        def step(self, kind, fresh):
            if kind == FREE and not fresh:
                self.u = 0.0                        # no (fresh) command: drive off
            self.sim.advance(self.u, self.period)
"""
from __future__ import annotations

import time

from .clock import ClockPublisher
from .lockstep import ADVANCE, FREE
from .plant_node import PlantNode
from .qos import publisher_qos
from .status import sim_values

__all__ = ["SimulatorNode", "ADVANCE", "FREE"]


class SimulatorNode(PlantNode):
    """Base of the simulator nodes.

    Attributes a subclass sets: ``sim`` (its plant, with the sim time ``sim.t`` in s), ``lock``
    (a :class:`~cablelab.ros.lockstep.LockStep`, or None to step on every timer tick),
    ``command`` (the name of its command input, whose freshness :meth:`step` is told),
    ``duration`` (sim time s after which the node is done, 0 = never), ``republish_every``
    (s wall between republished states while time waits, :meth:`PlantNode.may_step`).
    """

    lock = None
    command = "effort_commands"
    duration = 0.0
    republish_every = 0.5

    def __init__(self, name: str = "cable_sim_node", **node_kwargs):
        super().__init__(name, **node_kwargs)
        self.done = False
        self.pub_gate = None       # the state publisher the start gate counts subscribers of
        self.wait_subs = 0         # no start gate unless the node calls start_gate()
        self.last_publish = 0.0    # wall time of the last published state

    def state_publishers(self, *kinds_topics) -> list:
        """A publisher (the state QoS, :func:`~cablelab.ros.qos.publisher_qos`) per ``(message
        type, topic)``, in order; None for ``(type, None)`` (a topic switched off). The first is
        the one the start gate counts subscribers of."""
        pubs = [None if topic is None else self.create_publisher(kind, topic, publisher_qos())
                for kind, topic in kinds_topics]
        self.pub_gate = pubs[0]
        return pubs

    def start_simulation(self, desc, period: float, markers_topic: str, frame, markers_rate: float,
                         publish_first: bool = True) -> None:
        """The last call in ``__init__``: ``self.clock`` (/clock), ``desc`` published on
        /plant_description, then :meth:`PlantNode.start_stepping` (/diagnostics, ``self.timer``
        calling :meth:`tick` every ``period`` s wall, the 3D view ``frame()`` on
        ``markers_topic`` stamped with the sim time at ``markers_rate`` Hz wall and, with
        ``publish_first``, the initial state)."""
        self.period = period
        self.clock = ClockPublisher(self)
        self.publish_description(desc)
        self.start_stepping(period, markers_topic, frame, lambda: self.sim.t, markers_rate, publish_first=False)
        if publish_first:
            self._publish()

    def tick(self) -> None:
        """The timer: the start gate and, with a ``lock``, lock-step decide whether time moves
        now (:meth:`PlantNode.may_step`, without a lock :meth:`PlantNode.waiting_for_subscribers`);
        then :meth:`advance`."""
        kind = FREE
        if self.lock is not None:
            kind = self.may_step(self.lock, self.pub_gate, self.publish_state, self.republish_every)
            if kind is None:
                return
        elif self.waiting_for_subscribers(self.pub_gate, self.last_publish, self._publish, self.republish_every):
            return
        self.advance(kind)

    def advance(self, kind: str = ADVANCE) -> None:
        """One period (:meth:`step`; ``kind`` ADVANCE: the command answers the last state, FREE:
        real-time rules) and the new state out; at ``duration`` the node is done (the runner
        waits for the subscribers' acknowledgements, then stops it)."""
        if self.done:
            return
        self.step(kind, self.inputs.fresh(self.command, time.monotonic()))
        self._publish()
        self.done = bool(self.duration) and self.sim.t >= self.duration - 1e-9

    def _publish(self) -> None:
        """:meth:`publish_state`, its wall time kept (:attr:`last_publish`, the start gate's)."""
        self.publish_state()
        self.last_publish = time.monotonic()

    def step(self, kind: str, fresh: bool) -> None:
        """One period of physics (override); ``fresh``: the command input is fresh."""
        raise NotImplementedError

    def publish_state(self) -> None:
        """Publish the current state (override; with a ``lock``, call ``lock.published(t)``)."""
        raise NotImplementedError

    def extend_status(self, level, msg, values):
        return level, msg, sim_values(values, self.sim.t, self.lock)
