"""The MuJoCo model of the 5-DoF boom crane of 002 ch. 3 (tree: :mod:`cablelab.plants.crane.sim`),
built from a :class:`~cablelab.plants.crane.sim.CraneTruth`."""
from __future__ import annotations

import mujoco
import numpy as np


__all__ = ["build_mjcf", "gravity_in_base", "model_xml"]


def gravity_in_base(truth) -> np.ndarray:
    """(3,) gravity vector in the (tilted) crane base frame, m/s^2: R(tilt)^T [0, 0, -g]."""
    ex, ey = (float(v) for v in truth.base_tilt)
    cx, sx, cy, sy = np.cos(ex), np.sin(ex), np.cos(ey), np.sin(ey)
    rx = np.array([[1, 0, 0], [0, cx, -sx], [0, sx, cx]])
    ry = np.array([[cy, 0, sy], [0, 1, 0], [-sy, 0, cy]])
    return (ry @ rx).T @ np.array([0.0, 0.0, -truth.params.gravity])


def _f(x) -> str:
    return " ".join(repr(float(v)) for v in np.atleast_1d(x))


def model_xml(truth, kp=(0.0, 0.0, 0.0), kd=(0.0, 0.0, 0.0)) -> str:
    """MJCF text of the crane (see :mod:`cablelab.plants.crane.sim` for the tree)."""
    p = truth.params
    lb, lc = p.boom_length, p.counterbalance_distance
    b = truth.viscous
    c = truth.coulomb
    # boom point masses m_b at l_b/2 and m_c at -l_c as one inertial (about its centre, I_xx = 0)
    mb, mc = p.boom_mass, p.counterbalance_mass
    mtot = mb + mc
    xc = (mb * lb / 2 - mc * lc) / mtot
    jb = mb * (lb / 2 - xc) ** 2 + mc * (lc + xc) ** 2
    tiny = 1e-12 * max(jb, 1.0)  # MuJoCo needs inertia > mjMINVAL; 1e-12 relative is far below the tests
    ptiny = 1e-12 * p.payload_mass
    boom_inertial = (f'<inertial pos="{xc!r} 0 0" mass="{mtot!r}" '
                     f'diaginertia="{tiny!r} {jb + tiny!r} {jb + tiny!r}"/>')
    acts = "\n".join(
        f'<general name="{j}" joint="{j}" gainprm="1" biasprm="0 {-float(kp[i])!r} {-float(kd[i])!r}" '
        f'biastype="affine" ctrlrange="{-float(lim)!r} {float(lim)!r}"/>'
        for i, (j, lim) in enumerate(zip(("slew", "luff", "hoist"), truth.effort_limit)))
    return f"""<mujoco model="crane">
  <compiler angle="radian" autolimits="true" boundmass="0" boundinertia="0"/>
  <option timestep="{truth.timestep!r}" gravity="{_f(gravity_in_base(truth))}" integrator="RK4"/>
  <worldbody>
    <body name="turret">
      <joint name="slew" type="hinge" axis="0 0 1" damping="{b[0]!r}" frictionloss="{c[0]!r}"/>
      <inertial pos="0 0 0" mass="1" diaginertia="{p.slew_inertia / 2!r} {p.slew_inertia / 2!r} {p.slew_inertia!r}"/>
      <body name="boom">
        <joint name="luff" type="hinge" axis="0 -1 0" armature="{p.luff_inertia!r}"
               damping="{b[1]!r}" frictionloss="{c[1]!r}"/>
        {boom_inertial}
        <site name="tip" pos="{lb!r} 0 0"/>
        <body name="payload" pos="{lb!r} 0 0">
          <joint name="swing_y" type="hinge" axis="0 -1 0"/>
          <joint name="swing_x" type="hinge" axis="1 0 0"/>
          <joint name="hoist" type="slide" axis="0 0 -1" damping="{b[2]!r}" frictionloss="{c[2]!r}"
                 range="{float(truth.rope_range[0])!r} {float(truth.rope_range[1])!r}"/>
          <inertial pos="0 0 0" mass="{p.payload_mass!r}" diaginertia="{ptiny!r} {ptiny!r} {ptiny!r}"/>
          <site name="payload"/>
        </body>
      </body>
    </body>
  </worldbody>
  <actuator>
{acts}
  </actuator>
  <sensor>
    <jointpos joint="slew"/><jointpos joint="luff"/><jointpos joint="hoist"/>
    <jointvel joint="slew"/><jointvel joint="luff"/><jointvel joint="hoist"/>
    <actuatorfrc actuator="slew"/><actuatorfrc actuator="luff"/><actuatorfrc actuator="hoist"/>
    <jointpos joint="swing_y"/><jointpos joint="swing_x"/>
    <jointvel joint="swing_y"/><jointvel joint="swing_x"/>
    <framepos objtype="site" objname="tip"/><framequat objtype="body" objname="boom"/>
    <framepos objtype="site" objname="payload"/><framequat objtype="body" objname="payload"/>
  </sensor>
</mujoco>
"""


def build_mjcf(truth, kp=(0.0, 0.0, 0.0), kd=(0.0, 0.0, 0.0)) -> mujoco.MjModel:
    """Compiled MuJoCo model of the crane (actuators: motors, or PD servos with gains kp, kd)."""
    return mujoco.MjModel.from_xml_string(model_xml(truth, kp, kd))
