"""The MuJoCo model of the hopping leg (003): the body on a vertical slide joint with one motor."""
from __future__ import annotations

import mujoco

from .hybrid import LegParams


def build_mjcf(p: LegParams, dt: float) -> mujoco.MjModel:
    """The MuJoCo model: body on a vertical slide joint, one force motor, Euler at ``dt`` (s)."""
    xml = f"""
<mujoco model="leg">
  <option timestep="{float(dt)!r}" gravity="0 0 {-float(p.g)!r}" integrator="Euler"/>
  <worldbody>
    <body name="body">
      <joint name="hop" type="slide" axis="0 0 1" limited="false"/>
      <inertial pos="0 0 0" mass="{float(p.m)!r}" diaginertia="1e-6 1e-6 1e-6"/>
    </body>
  </worldbody>
  <actuator>
    <motor name="motor" joint="hop" gear="1" ctrllimited="false"/>
  </actuator>
</mujoco>"""
    return mujoco.MjModel.from_xml_string(xml)
