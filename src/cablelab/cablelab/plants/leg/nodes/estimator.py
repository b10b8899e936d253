"""Leg estimator node: ``/leg/joint_states`` (+ ``/leg/contact`` when present) ->
:class:`~..estimator.HopEstimator` -> ``/leg/hop_estimate``; /diagnostics reports the phase
source, chattering flips, switch/height disagreements and dropouts.

A state and the switch reading of its sample come on two topics, in either order: a state whose
sample's switch reading has not arrived yet (the switch streams, its last reading is older)
waits for it, or for the next state (then it goes with the last reading). Taking the last
reading at once gave the touch-down sample the flight phase whenever the state came first, a
stance torque one sample late at random touch-downs of a lock-stepped run.

Parameters: :data:`.parameters.ESTIMATOR`.
"""
from __future__ import annotations

import time

from sensor_msgs.msg import JointState

from . import hop_msg
from .. import topics
from ..description import leg_of, load_leg_description
from ..estimator import HopEstimator
from ....ros import convert
from ....ros.plant_node import PlantNode
from ....ros.qos import publisher_qos, stream_qos
from .parameters import ESTIMATOR as PARAMETERS


class LegEstimatorNode(PlantNode):
    def __init__(self):
        super().__init__("payload_estimator")
        v = self.declare_params(PARAMETERS)
        self.description = load_leg_description(v.description)
        params = leg_of(self.description).params(self.description.gravity)
        self.est = HopEstimator(params, h=v.h, f_on=v.f_on)
        self.contact = None
        self.contact_t = None          # stamp of the last switch reading
        self.pending = None            # (t, z, tau) of a state waiting for its switch reading
        self.inputs.add("joint_states", timeout=0.5)
        self.inputs.add("contact", timeout=0.5, length=1, required=False)
        self.pub = self.create_publisher(JointState, topics.HOP_ESTIMATE, publisher_qos())
        self.create_subscription(JointState, topics.JOINT_STATES, self.on_state, stream_qos())
        self.create_subscription(JointState, topics.CONTACT, self.on_contact, stream_qos())
        self.start_diagnostics()

    def extend_status(self, level, msg, values):
        e = self.est
        values.update({"phase source": "height (no contact switch)" if self.contact is None else "contact switch",
                       "chattering flips": str(e.flips), "switch/height disagreements": str(e.disagreements),
                       "dropouts": str(e.dropouts)})
        if self.contact is None:
            msg = "; ".join(x for x in (msg, "no /leg/contact: phase from height") if x)
            level = max(level, 1)
        return level, msg or "ok", values

    def on_contact(self, msg: JointState) -> None:
        t, _, pos, _, _ = convert.joint_state_arrays(msg)
        if self.accept("contact", pos):
            self.contact, self.contact_t = float(pos[0]), t
            if self.pending is not None and self.pending[0] <= t + 1e-6:
                self.estimate(*self.pending)

    def on_state(self, msg: JointState) -> None:
        t, names, pos, _, eff = convert.joint_state_arrays(msg)
        if pos is None or "body" not in names or not self.accept("joint_states", pos):
            self.est.dropouts += 1
            return
        z = float(pos[names.index("body")])
        tau = float(eff[names.index("motor")]) if eff is not None and "motor" in names and len(eff) == len(names) else None
        if self.pending is not None:             # its reading never came: the last one
            self.estimate(*self.pending)
        if self.contact_t is not None and t > self.contact_t + 1e-6 and \
                self.inputs.fresh("contact", time.monotonic()):
            self.pending = (t, z, tau)           # the switch of this sample is on its way
            return
        self.estimate(t, z, tau)

    def estimate(self, t: float, z: float, tau: float | None) -> None:
        """One sample into the estimator with the last switch reading (if fresh); publish."""
        self.pending = None
        contact = self.contact if self.inputs.fresh("contact", time.monotonic()) else None
        e = self.est.step(t, z, contact, tau)
        self.pub.publish(hop_msg(t, e.z, e.zd, e.phase, e.apex_height, e.apex_time, e.grf))


def make_node() -> PlantNode:
    return LegEstimatorNode()
