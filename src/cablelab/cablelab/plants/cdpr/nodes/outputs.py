"""The CDPR's state topics as pre-serialised messages (:class:`cablelab.ros.rawmsg.RawTemplate`),
published by the simulator node and the control loop, and the payload estimate of the estimator
node: each sample patches stamps and numbers."""
from __future__ import annotations

import numpy as np
from geometry_msgs.msg import InertiaStamped, PoseStamped
from rosgraph_msgs.msg import Clock
from sensor_msgs.msg import JointState
from std_msgs.msg import Float64MultiArray
from trajectory_msgs.msg import MultiDOFJointTrajectory

from ....ros import convert
from ....ros.qos import publisher_qos
from ....ros.rawmsg import CommandTemplate, RawTemplate
from ....rotations import wxyz_to_xyzw
from .. import topics


def fill_pose(tpl: RawTemplate, t: float, position, quat_wxyz) -> RawTemplate:
    tpl.stamp(t)
    tpl.vector("pose.position")[:] = position
    tpl.vector("pose.orientation", "xyzw")[:] = wxyz_to_xyzw(quat_wxyz)
    return tpl


def estimate_template() -> RawTemplate:
    """The ``/cdpr/payload_estimate`` InertiaStamped (com z NaN: the estimator finds x_G, y_G)."""
    return RawTemplate(convert.inertia_msg(0.0, 0.0, [0.0, 0.0, float("nan")]))


def fill_estimate(tpl: RawTemplate, t: float, mass: float, com) -> RawTemplate:
    """The estimate of stamp ``t``: ``mass`` kg and the centre of mass x, y (``com[:2]``), m."""
    tpl.stamp(t)
    tpl["inertia.m"][0] = mass
    tpl.vector("inertia.com")[:2] = com[:2]
    return tpl


class CdprOutputs:
    """Publishers and templates of ``n`` winches: joint states, cable tensions, reference, /clock,
    measured pose, ground truth (``truth``) and effort commands (``commands``); without ``state``
    no joint states, tensions and reference publishers (another publishes them from the
    templates: the simulator's compiled path)."""

    def __init__(self, node, n: int, truth: bool = True, commands: bool = False, state: bool = True):
        q = publisher_qos()
        make = node.create_publisher
        self.pub_js = self.pub_ten = self.pub_ref = None
        if state:
            self.state_publishers(node)
        self.pub_pose = make(PoseStamped, topics.PLATFORM_POSE, q)
        self.pub_cmd = make(Float64MultiArray, topics.EFFORT_COMMANDS, q) if commands else None
        self.pub_tpose = make(PoseStamped, topics.GROUND_TRUTH_POSE, q) if truth else None
        self.pub_tpay = make(InertiaStamped, topics.GROUND_TRUTH_PAYLOAD, q) if truth else None
        self.pub_clock = make(Clock, "/clock", publisher_qos())
        z, z3, unit = np.zeros(n), np.zeros(3), [0.0, 0.0, 0.0, 1.0]
        self.t_js = RawTemplate(convert.joint_state_msg(0.0, [f"winch_{i}" for i in range(1, n + 1)], z, z, z))
        self.t_ten = RawTemplate(convert.joint_state_msg(0.0, [f"cable_{i}" for i in range(1, n + 1)], z, None, z))
        self.t_ref = RawTemplate(convert.multidof_msg(0.0, z3, unit, z3, None, z3, None))
        self.ref_views = (self.t_ref.vector("points[0].transforms[0].translation"),
                          self.t_ref.vector("points[0].velocities[0].linear"),
                          self.t_ref.vector("points[0].accelerations[0].linear"))
        self.t_cmd = CommandTemplate("winch")
        self.t_clock = RawTemplate(convert.clock_msg(0.0))
        self.t_pose = RawTemplate(convert.pose_msg(0.0, z3, unit))
        self.t_tpose = RawTemplate(convert.pose_msg(0.0, z3, unit))
        self.t_tpay = RawTemplate(convert.inertia_msg(0.0, 0.0, z3))

    def state_publishers(self, node) -> None:
        """The joint states, tensions and reference publishers."""
        q = publisher_qos()
        self.pub_js = node.create_publisher(JointState, topics.JOINT_STATES, q)
        self.pub_ten = node.create_publisher(JointState, topics.CABLE_TENSIONS, q)
        self.pub_ref = node.create_publisher(MultiDOFJointTrajectory, topics.REFERENCE, q)

    def payload(self, mass: float, com) -> None:
        """The true moving mass (kg) and centre of mass (3,) of the ground truth."""
        self.t_tpay["inertia.m"][0] = mass
        self.t_tpay.vector("inertia.com")[:] = com

    def reference(self, t: float, pos, vel, acc) -> None:
        for view, value in zip(self.ref_views, (pos, vel, acc)):
            view[:] = value
        self.t_ref.stamp(t)
        self.pub_ref.publish(self.t_ref.data())

    def joints(self, t: float, angle, rate, torque) -> None:
        self.pub_js.publish(self.joint_bytes(t, angle, rate, torque))

    def joint_bytes(self, t: float, angle, rate, torque) -> bytes:
        """The serialised joint states (motor angles, rates, torques of the winches) of stamp ``t``."""
        js = self.t_js
        js.stamp(t)
        js["position"][:], js["velocity"][:], js["effort"][:] = angle, rate, torque
        return js.data()

    def tensions(self, t: float, tension, length=None) -> None:
        ten = self.t_ten
        ten.stamp(t)
        ten["effort"][:] = tension
        if length is not None:
            ten["position"][:] = length
        self.pub_ten.publish(ten.data())

    def command(self, t: float, torques) -> None:
        self.pub_cmd.publish(self.t_cmd.data(torques, t))

    def simulator_sample(self, stepper, pose: bool = True, extras: bool = True) -> None:
        """One sample of the simulator node (a :class:`~cablelab.plants.cdpr.stepping.SimStepper`
        at its present sim time), all of it now: :meth:`state_sample`, its joint states
        published, then :meth:`rest_sample`."""
        joints, rest = self.state_sample(stepper, pose, extras)
        self.pub_js.publish(joints)
        self.rest_sample(rest)

    def state_sample(self, stepper, pose: bool = True, extras: bool = True) -> tuple[bytes, tuple]:
        """The measurements at the stepper's present sim time: the reference samples due before
        the state are published, the joint states are serialised (``joints``: the bytes to
        publish on :attr:`pub_js`); ``rest`` is what :meth:`rest_sample` publishes after them
        (cable tensions, the reference samples due after the state, and with ``extras`` /clock,
        the measured pose (``pose``) and the ground truth: off the controller's path)."""
        sim, t = stepper.sim, stepper.sim.time
        ms = sim.measure()
        before, after = stepper.reference_stamps(t)
        for tr in before:
            self.reference(tr, *stepper.reference.at(tr))
        rest = (t, ms["tension"], ms["cable_length"], [(tr, stepper.reference.at(tr)) for tr in after],
                ((ms["position"], ms["quat"]) if pose else None, sim.truth_pose()) if extras else None)
        return self.joint_bytes(t, ms["motor_angle"], ms["motor_velocity"], ms["motor_torque"]), rest

    def rest_sample(self, rest: tuple) -> None:
        """Publish the ``rest`` of a :meth:`state_sample`."""
        t, tension, length, refs, extras = rest
        self.tensions(t, tension, length)
        for tr, ref in refs:
            self.reference(tr, *ref)
        if extras is not None:
            self.extras(t, *extras)

    def extras(self, t: float, pose=None, truth=None) -> None:
        """/clock, the measured pose ``(position, quat wxyz)`` and the ground truth pose (and
        payload) when given."""
        self.t_clock.stamp(t, "clock")
        self.pub_clock.publish(self.t_clock.data())
        if pose is not None:
            self.pub_pose.publish(fill_pose(self.t_pose, t, *pose).data())
        if truth is not None:
            self.pub_tpose.publish(fill_pose(self.t_tpose, t, *truth).data())
            self.t_tpay.stamp(t)
            self.pub_tpay.publish(self.t_tpay.data())
