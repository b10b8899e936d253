"""The MuJoCo model of the plant: :func:`build_mjcf` (MJCF text) and the name of its joint."""
from __future__ import annotations

JOINT = "hinge"   #: the joint's name in the model and on the joint-state topic


def build_mjcf(section, damping: float = 0.0, timestep: float = 0.001) -> str:
    """A hinge about world y with a point-like bob ``length`` below it (q = 0 hanging down),
    torque-driven; ``damping`` (N m s/rad) is the simulated truth the nominal model lacks."""
    m, l = section.mass, section.length
    return f"""<mujoco><option timestep="{timestep!r}" integrator="implicitfast" gravity="0 0 -9.81"/>
  <worldbody><body><joint name="{JOINT}" type="hinge" axis="0 -1 0" damping="{damping!r}"/>
    <geom type="sphere" size="0.01" pos="0 0 -{l!r}" mass="{m!r}"/></body></worldbody>
  <actuator><motor joint="{JOINT}" name="tau"/></actuator></mujoco>"""
