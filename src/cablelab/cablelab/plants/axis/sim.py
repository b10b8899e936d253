"""MuJoCo model of the single axis (CONTRACT ``/axis``): one slide or hinge joint with inertia,
viscous damping, Coulomb friction (MuJoCo ``frictionloss``) and, for a revolute joint, a
gravity load ``m c g sin(q)`` with q = 0 hanging down (CONTRACT section 3, ``axis``).

Equation of motion simulated (the inverse model of :mod:`cablelab.plants.axis`):

    u = M qdd + Fv qd + Fc sign(qd) (+ m c g sin q)

``u`` is the motor force/torque (N or N m) set as ``ctrl`` of a gear-1 motor. The measured
effort the simulator reports is ``u + offset`` (a torque-sensor bias, effect
``torque_sensor_offset``).
"""
from __future__ import annotations

from dataclasses import dataclass

from ...errors import CablelabError


@dataclass(frozen=True)
class AxisTruth:
    """True parameters of a simulated axis (SI).

    Args:
        inertia: M, kg (prismatic) or kg m^2 (revolute), total reflected inertia
        viscous: Fv, N s/m or N m s/rad
        coulomb: Fc, N or N m (MuJoCo frictionloss, a soft constraint)
        offset: bias added to the reported effort, N or N m
        timestep: physics step, s
    """

    inertia: float = 2.0
    viscous: float = 5.0
    coulomb: float = 1.0
    offset: float = 0.0
    timestep: float = 0.001


#: the simulator node's description without a ``description`` parameter
DEFAULT_DESCRIPTION = ("plant: axis\nname: simulated linear axis\ngravity: 9.81\n"
                       "axis:\n  joint_type: prismatic\n  inertia: 2.0\n")


def truth_from_parameters(description, v) -> AxisTruth:
    """The true axis of the simulator node's parameters ``v`` (:data:`.nodes.parameters.SIM`):
    an ``inertia`` of NaN is the description's ``axis.inertia``, else 2."""
    nominal = description.axis.inertia if description.axis else None
    inertia = v.inertia if v.inertia == v.inertia else float(nominal or 2.0)
    return AxisTruth(inertia=inertia, viscous=v.viscous, coulomb=v.coulomb, offset=v.offset,
                     timestep=v.timestep)


def pendulum_arm(inertia: float, gravity_moment: float) -> tuple[float, float]:
    """(c m, m kg) of the revolute axis's point mass: m c = ``gravity_moment`` with c at most 1 m
    and half of ``inertia`` at most in m c^2 (so the armature stays positive); (0, 1e-6) without
    a gravity load."""
    gm = float(gravity_moment)
    if gm > 0:
        c = min(1.0, 0.5 * float(inertia) / gm)
        return c, gm / c
    return 0.0, 1e-6


def axis_mjcf(joint_type: str, truth: AxisTruth, gravity_moment: float = 0.0,
              gravity: float = 9.81) -> str:
    """MJCF text of the axis.

    Prismatic: a body of mass M sliding along world x (horizontal: no gravity load).
    Revolute: a hinge about world y; a point mass m at distance c below the pivot with
    m c = ``gravity_moment`` (so the load is m c g sin q) and the rest of M as joint armature.
    """
    if truth.inertia <= 0 or truth.viscous < 0 or truth.coulomb < 0 or truth.timestep <= 0:
        raise CablelabError(f"axis simulator: invalid parameters {truth}")
    opt = (f'<option timestep="{truth.timestep!r}" gravity="0 0 {-gravity!r}" '
           f'integrator="implicitfast"/>')
    joint_common = f'damping="{truth.viscous!r}" frictionloss="{truth.coulomb!r}"'
    if joint_type == "prismatic":
        body = (f'<body name="load"><joint name="joint" type="slide" axis="1 0 0" {joint_common}/>'
                f'<inertial pos="0 0 0" mass="{truth.inertia!r}" diaginertia="1e-3 1e-3 1e-3"/>'
                f'<geom type="box" size="0.05 0.05 0.05" contype="0" conaffinity="0"/></body>')
    elif joint_type == "revolute":
        gm = float(gravity_moment)
        if gm < 0:
            raise CablelabError(f"axis simulator: gravity_moment must be >= 0, got {gm}")
        c, m = pendulum_arm(truth.inertia, gm)
        armature = truth.inertia - m * c * c
        body = (f'<body name="load"><joint name="joint" type="hinge" axis="0 1 0" '
                f'armature="{armature!r}" {joint_common}/>'
                f'<inertial pos="0 0 {-c!r}" mass="{m!r}" diaginertia="1e-9 1e-9 1e-9"/>'
                f'<geom type="sphere" size="0.02" pos="0 0 {-c!r}" contype="0" conaffinity="0"/></body>')
    else:
        raise CablelabError(f"axis.joint_type: expected 'revolute' or 'prismatic', got {joint_type!r}")
    return (f'<mujoco model="axis">{opt}<worldbody>{body}</worldbody>'
            f'<actuator><motor name="drive" joint="joint" gear="1" ctrllimited="false"/></actuator>'
            f'</mujoco>')


class AxisSim:
    """A running axis simulation: ``advance(u, duration)`` holds the motor command u for
    ``duration`` s (whole physics steps) and returns (t, q, qd)."""

    def __init__(self, description, truth: AxisTruth | None = None):
        import mujoco

        if description.axis is None:
            raise CablelabError("axis simulator: the description has no 'axis' section")
        ax = description.axis
        self.truth = truth or AxisTruth(inertia=ax.inertia or AxisTruth.inertia)
        self.model = mujoco.MjModel.from_xml_string(
            axis_mjcf(ax.joint_type, self.truth, ax.gravity_moment, description.gravity))
        self.data = mujoco.MjData(self.model)
        self._mujoco = mujoco

    @property
    def t(self) -> float:
        return float(self.data.time)

    def state(self) -> tuple[float, float, float]:
        """(t s, q, qd)."""
        return float(self.data.time), float(self.data.qpos[0]), float(self.data.qvel[0])

    def advance(self, u: float, duration: float) -> tuple[float, float, float]:
        n = max(1, int(round(duration / self.model.opt.timestep)))
        self.data.ctrl[0] = float(u)
        self._mujoco.mj_step(self.model, self.data, nstep=n)
        return self.state()

    def measured_effort(self, u: float) -> float:
        """The effort a sensor reports for command u (with the sensor offset)."""
        return float(u) + self.truth.offset
