"""Live payload estimator of any MuJoCo model: ``payload_estimator --plant mjcf``.

Takes the machine from ``/plant_description`` (or ``-p description:=FILE``), then listens to
its ``joint_states`` (names as in the model, remapping of ``mjcf.topics`` honoured) and, every
``publish_every`` messages, fits the payload on ``mjcf.payload_body`` over the last ``window``
seconds (:func:`..estimation.payload_estimate`: MuJoCo's inverse dynamics and its payload
columns) and publishes ``payload_estimate`` (geometry_msgs/InertiaStamped: ``m``, ``com`` in
the payload body's frame). A message whose names, lengths or values do not fit the model is
rejected and counted on /diagnostics.
"""
from __future__ import annotations

import time
from collections import deque

import numpy as np
from geometry_msgs.msg import InertiaStamped
from sensor_msgs.msg import JointState

from ....errors import CablelabError
from ....ros import convert
from ....ros.params import DESCRIPTION, Param
from ....ros.plant_node import PlantNode
from ....ros.qos import catch_up_qos, publisher_qos
from ..estimation import payload_estimate
from ..mjcf import actuated_joints, dof_joints
from ..topics import topic

PARAMETERS = (
    DESCRIPTION,
    Param("window", 4.0, "length of the sliding window fitted", "s", gt=0.5, le=3600.0),
    Param("publish_every", 200, "fit and publish every this many joint-state messages", ge=1,
          le=10 ** 9),
)


class MjcfEstimator(PlantNode):
    def __init__(self):
        super().__init__("payload_estimator")
        v = self.declare_params(PARAMETERS)
        self.window, self.every = v.window, v.publish_every
        self.joints: list[str] = []
        self.buf: deque = deque()
        self.count = 0
        self.last = None
        self.problem = ""
        self.pub = None
        self.listen_for_description(v.description)
        self.start_diagnostics()

    def set_description(self, desc) -> None:
        sec = getattr(desc, "mjcf", None)
        if sec is None or not sec.payload_body or self.pub is not None:
            if sec is None or not sec.payload_body:
                self.description_problem = "the description names no mjcf.payload_body"
            return
        super().set_description(desc)
        model = sec.compiled()
        self.joints = dof_joints(model)
        self.driven = np.array([j in set(sec.joints or actuated_joints(model)) for j in self.joints])
        self.inputs.add("joint_states", timeout=0.5, length=2 * len(self.joints))
        self.pub = self.create_publisher(InertiaStamped, topic(sec, "payload_estimate"), publisher_qos())
        self.create_subscription(JointState, topic(sec, "joint_states"), self.on_state, catch_up_qos())

    def extend_status(self, level, msg, values):
        values["samples in window"] = str(len(self.buf))
        if self.last is not None:
            values["payload mass kg"] = f"{self.last.m:.6g}"
        if self.problem:
            values["last fit"] = self.problem
        return level, msg, values

    def on_state(self, msg: JointState) -> None:
        t, names, q, _qd, eff = convert.joint_state_arrays(msg)
        ok = names is not None and list(names) == self.joints and q is not None and eff is not None \
            and q.size == len(self.joints) and eff.size == len(self.joints)
        both = np.concatenate([q, np.where(self.driven, eff, 0.0)]) if ok else None
        if not self.inputs.accept("joint_states", both, time.monotonic()):
            return
        if self.buf and not t > self.buf[-1][0]:
            return                                     # repeated or older stamp
        self.buf.append((t, q.copy(), np.where(self.driven, eff, 0.0)))
        while self.buf and self.buf[-1][0] - self.buf[0][0] > self.window:
            self.buf.popleft()
        self.count += 1
        if self.count % self.every == 0:
            self.estimate()

    def estimate(self) -> None:
        t = np.array([b[0] for b in self.buf])
        if len(t) < 60 or t[-1] - t[0] < 0.5 * self.window:
            return
        q = np.array([b[1] for b in self.buf])
        eff = np.array([b[2] for b in self.buf])
        try:
            est = payload_estimate(t, q, eff, self.description, driven=self.driven)
        except CablelabError as exc:
            self.problem = " ".join(str(exc).split())
            return
        self.problem, self.last = "", est
        self.pub.publish(convert.inertia_msg(float(t[-1]), est.m, est.com,
                                             frame_id=self.description.mjcf.payload_body))


def make_node() -> PlantNode:
    return MjcfEstimator()
