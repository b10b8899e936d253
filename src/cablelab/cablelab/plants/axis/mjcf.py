"""The compiled MuJoCo axis for synthetic data and simulation-based fits (sensors: position and
actuator force)."""
from __future__ import annotations

from .sim import AxisTruth, axis_mjcf


def build_mjcf(description, truth: AxisTruth, servo: tuple[float, float] | None = None):
    """Compiled MuJoCo axis (:func:`~cablelab.plants.axis.sim.axis_mjcf`) for synthetic data and
    simulation-based fits, with sensors ``[q, actuator force]``.

    Integration is explicit semi-implicit Euler with Euler damping off, so the force a sensor reports
    is the force applied over the step (implicit integrators fold dt * (damping + servo kv) into
    the inertia; RK4 re-evaluates a servo inside the step; both bias the "true" M and Fv by a few %
    against u = M qdd + ...). The friction-loss constraint is stiff (Fc sign(qd) down to ~1e-4 m/s
    instead of the default soft ramp that looks like extra viscous friction near reversals).

    Args:
        servo: ``(kp, kv)``: the actuator is a position servo whose control is the reference
            position; None: a force/torque motor whose control is the effort.
    """
    import mujoco

    ax = description.axis
    spec = mujoco.MjSpec.from_string(axis_mjcf(ax.joint_type, truth, ax.gravity_moment,
                                               description.gravity))
    spec.option.integrator = mujoco.mjtIntegrator.mjINT_EULER
    spec.option.disableflags |= mujoco.mjtDisableBit.mjDSBL_EULERDAMP
    joint = spec.joints[0]
    joint.solref_friction[:] = [2 * truth.timestep, 1.0]
    joint.solimp_friction[:3] = [0.99, 0.99, 0.001]
    if servo is not None:
        kp, kv = servo
        act = spec.actuators[0]
        act.gaintype = mujoco.mjtGain.mjGAIN_FIXED
        act.gainprm[0] = kp
        act.biastype = mujoco.mjtBias.mjBIAS_AFFINE
        act.biasprm[0:3] = [0.0, -kp, -kv]
    spec.add_sensor(type=mujoco.mjtSensor.mjSENS_JOINTPOS, objtype=mujoco.mjtObj.mjOBJ_JOINT,
                    objname="joint")
    spec.add_sensor(type=mujoco.mjtSensor.mjSENS_ACTUATORFRC, objtype=mujoco.mjtObj.mjOBJ_ACTUATOR,
                    objname="drive")
    return spec.compile()
