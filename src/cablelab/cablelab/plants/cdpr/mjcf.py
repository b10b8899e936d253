"""The MuJoCo model of a suspended CDPR built from any plant description (CONTRACT section 3):
winches on their swivel axes, real pulleys when the description has a sheave radius, the
platform and its payload (:class:`~cablelab.plants.cdpr.sim.CdprTruth` the true parameters)."""
from __future__ import annotations

import mujoco
import numpy as np

from ...description import Description
from ...errors import CablelabError
from .geometry import matrix_to_quat, swivel_reference


__all__ = ["FRICTION_SOLIMP", "RUN_LENGTH", "build_mjcf", "model_xml"]


RUN_LENGTH = 20.0  # m of cable between the winch carriage (at s = 0) and A_i along the swivel axis (longer
#              than any reel-out, so the carriage never reaches the sheave)


FRICTION_SOLIMP = "0.9999 0.9999 0.001"   # near-hard Coulomb friction on the winches


def _frame_quat(z: np.ndarray, x: np.ndarray) -> np.ndarray:
    y = np.cross(z, x)
    R = np.stack([x, y, z], 1)
    return matrix_to_quat(R)


def _fmt(v) -> str:
    return " ".join(f"{float(x):.9g}" for x in np.ravel(v))


def model_xml(desc: Description, truth) -> str:
    """MJCF text of the CDPR (cable limits still open; :class:`CdprSim` closes them)."""
    if desc.cdpr is None:
        raise CablelabError("plant description: no 'cdpr' section")
    c = desc.cdpr
    t = truth.resolved(desc)
    k = c.gear_ratio / c.drum_radius                       # motor rad per m of cable
    r = t.pulley_radius
    sx, sy, sz = t.platform_size
    mp = t.platform_mass
    inertia = mp / 12.0 * np.array([sy * sy + sz * sz, sx * sx + sz * sz, sx * sx + sy * sy])
    axes = c.swivel_axes
    refs = swivel_reference(axes)
    bodies, tendons, actuators, sensors = [], [], [], []
    for i, cab in enumerate(c.cables, start=1):
        A, z, x = cab.exit_point, axes[i - 1], refs[i - 1]
        quat = _frame_quat(z, x)
        bodies.append(
            f'<body name="winch_{i}" pos="{_fmt(A - RUN_LENGTH * z)}" quat="{_fmt(quat)}" gravcomp="1">'
            f'<joint name="reel_{i}" type="slide" axis="0 0 -1" armature="{t.motor_inertia * k * k:.9g}" '
            f'frictionloss="{t.winch_coulomb * k:.9g}" solimpfriction="{FRICTION_SOLIMP}" '
            f'damping="{t.winch_viscous * k * k:.9g}"/>'
            f'<geom type="sphere" size="0.02" mass="0.1"/><site name="reel_{i}"/></body>')
        if t.pulleys:
            bodies.append(
                f'<body name="pulley_{i}" pos="{_fmt(A)}" quat="{_fmt(quat)}">'
                f'<joint name="swivel_{i}" type="hinge" axis="0 0 1" armature="0.05" damping="2"/>'
                f'<geom name="sheave_{i}" type="cylinder" size="{r:.9g} 0.01" pos="{r:.9g} 0 0" '
                f'euler="90 0 0" mass="2"/>'
                f'<site name="in_{i}" pos="{-0.5 * r:.9g} 0 {1.5 * r:.9g}"/>'
                f'<site name="out_{i}" pos="{2.5 * r:.9g} 0 {1.5 * r:.9g}"/>'
                f'<site name="rim_{i}" pos="{r:.9g} 0 {1.001 * r:.9g}"/></body>')
            path = (f'<site site="reel_{i}"/><geom geom="sheave_{i}" sidesite="in_{i}"/>'
                    f'<site site="rim_{i}"/><geom geom="sheave_{i}" sidesite="out_{i}"/>'
                    f'<site site="anchor_{i}"/>')
        else:
            bodies.append(f'<site name="exit_{i}" pos="{_fmt(A)}"/>')
            path = f'<site site="reel_{i}"/><site site="exit_{i}"/><site site="anchor_{i}"/>'
        tendons.append(f'<spatial name="cable_{i}" limited="true" range="0 1000" '
                       f'solreflimit="{t.cable_timeconst:.9g} 1" solimplimit="0.95 0.99 0.001" '
                       f'width="0.005">{path}</spatial>')
        actuators.append(f'<motor name="motor_{i}" joint="reel_{i}" gear="{k:.9g}" ctrllimited="false"/>')
        sensors.append(f'<tendonlimitfrc name="tension_{i}" tendon="cable_{i}"/>')
    anchors = "".join(f'<site name="anchor_{i}" pos="{_fmt(cab.anchor_point)}"/>'
                      for i, cab in enumerate(c.cables, start=1))
    payload = ""
    if t.payload_mass > 0:
        ml = t.payload_mass
        payload = (f'<body name="payload" pos="{_fmt(t.payload_com)}">'
                   f'<inertial pos="0 0 0" mass="{ml:.9g}" diaginertia="{_fmt(ml / 12 * np.array([0.5, 0.5, 0.8]))}"/>'
                   f'<geom type="box" size="0.5 0.4 0.05" mass="0" rgba="0.5 0.5 0.6 1"/></body>')
    return f"""<mujoco model="cdpr">
  <compiler angle="degree" autolimits="true"/>
  <option timestep="{t.timestep:.9g}" gravity="0 0 {-desc.gravity:.9g}" integrator="implicitfast">
    <flag contact="disable"/>
  </option>
  <default><geom contype="0" conaffinity="0"/></default>
  <worldbody>
    {''.join(bodies)}
    <body name="platform" pos="0 0 1">
      <freejoint name="platform"/>
      <inertial pos="{_fmt(t.platform_com)}" mass="{mp:.9g}" diaginertia="{_fmt(inertia)}"/>
      <geom type="box" size="{sx / 2:.9g} {sy / 2:.9g} {sz / 2:.9g}" mass="0" rgba="0.7 0.5 0.2 0.6"/>
      {anchors}{payload}
    </body>
  </worldbody>
  <tendon>{''.join(tendons)}</tendon>
  <actuator>{''.join(actuators)}</actuator>
  <sensor>{''.join(sensors)}</sensor>
</mujoco>"""


def build_mjcf(desc: Description, truth) -> mujoco.MjModel:
    """The compiled MuJoCo CDPR of :func:`model_xml` (cable limits still open; :class:`CdprSim`
    closes them)."""
    return mujoco.MjModel.from_xml_string(model_xml(desc, truth))
