"""CAROCA written as MJCF from the cdpr plant's description (``plants/cdpr/data/caroca.yaml``):
``caroca.xml`` is what :func:`caroca_xml` writes (``./run python -m
cablelab.plants.mjcf.examples.caroca`` rewrites it; with ``CDPR_BAG OUT`` it writes
:func:`mjcf_bag`).

The platform moves in six joints (x, y, z slides in the world, then intrinsic yaw-pitch-roll
hinges z, y, x: the pose of ``/cdpr/platform_pose`` as joint angles). Each cable is a spatial
tendon that comes up its post along the swivel axis to the sheave and leaves it towards its
anchor B_i on the platform from the tangent point A'_i of the swivel pulley (001 eq. 6-9,
:func:`cablelab.plants.cdpr.geometry.cable_geometry`) computed for the platform at ``home``, a
fixed site: the tendon's direction at the platform, the only part the forces use, is the
pulley model's up to the tangent point's travel over the workspace (a few cm on 3-6 m cables).
A sheave as wrapping geometry would follow it, but a MuJoCo sphere or cylinder wraps only a
straight path that crosses it, and the cable arriving along the swivel axis touches the sheave
only tangentially. The pulley's wrap length is not modelled (constant per cable at ``home``).
No actuator: the measured cable tensions move the platform (``mjcf.tendons``).
"""
from __future__ import annotations

from pathlib import Path

import numpy as np

HERE = Path(__file__).resolve().parent
#: the shipped file
CAROCA = HERE / "caroca.xml"
#: the platform position the sheaves are oriented for (the middle of the reference trajectories)
HOME = (0.0, 0.0, 0.6)


def _v(x) -> str:
    return " ".join(f"{float(c):.6g}" for c in x)


def caroca_xml(section=None, home=HOME) -> str:
    """The MJCF text of a CDPR from its ``cdpr:`` section (default: CAROCA's)."""
    if section is None:
        from ...cdpr.description import parse_section
        import yaml

        data = yaml.safe_load((HERE.parents[1] / "cdpr" / "data" / "caroca.yaml").read_text())
        section = parse_section(data["cdpr"])
    from ...cdpr.geometry import cable_geometry

    A = np.array([c.exit_point for c in section.cables], float)
    B = np.array([c.anchor_point for c in section.cables], float)
    z = np.array([c.swivel_axis for c in section.cables], float)
    z = z / np.linalg.norm(z, axis=1, keepdims=True)
    exits = cable_geometry(A, B, np.asarray(home, float), None, float(section.pulley_radius or 0.0),
                           z).tangent_points[0]
    sites, anchors, tendons = [], [], []
    for i in range(1, len(A) + 1):
        sites.append(f'    <site name="post_{i}" pos="{_v(A[i - 1] - z[i - 1])}"/>')
        sites.append(f'    <site name="exit_{i}" pos="{_v(exits[i - 1])}"/>')
        anchors.append(f'      <site name="anchor_{i}" pos="{_v(B[i - 1])}"/>')
        tendons.append(f'    <spatial name="cable_{i}"><site site="post_{i}"/><site site="exit_{i}"/>'
                       f'<site site="anchor_{i}"/></spatial>')
    m = float(section.platform_mass or 1.0)
    ixx, izz = m / 12 * (1.5**2 + 1.0**2), m / 12 * (1.5**2 + 1.5**2)
    nl = "\n"
    return f"""<!-- CAROCA, the 8-cable suspended CDPR of the cdpr plant, as MJCF (written by caroca.py from
     plants/cdpr/data/caroca.yaml; see its docstring). -->
<mujoco model="caroca">
  <compiler angle="radian"/>
  <option timestep="0.02" gravity="0 0 -9.81"/>
  <default><geom contype="0" conaffinity="0" rgba="0.6 0.6 0.7 1"/><site size="0.03"/></default>
  <worldbody>
{nl.join(sites)}
    <body name="platform">
      <joint name="x" type="slide" axis="1 0 0"/>
      <joint name="y" type="slide" axis="0 1 0"/>
      <joint name="z" type="slide" axis="0 0 1"/>
      <joint name="yaw" type="hinge" axis="0 0 1"/>
      <joint name="pitch" type="hinge" axis="0 1 0"/>
      <joint name="roll" type="hinge" axis="1 0 0"/>
      <inertial pos="0 0 0" mass="{m:g}" diaginertia="{ixx:.6g} {ixx:.6g} {izz:.6g}"/>
      <geom type="box" size="0.75 0.75 0.5" rgba="0.6 0.6 0.7 0.3"/>
{nl.join(anchors)}
    </body>
  </worldbody>
  <tendon>
{nl.join(tendons)}
  </tendon>
</mujoco>
"""


#: the platform's six joints in the model, in order
JOINTS = ("x", "y", "z", "yaw", "pitch", "roll")


def mjcf_bag(cdpr_bag, out) -> str:
    """A CDPR bag for the ``mjcf`` plant with this model: its measured pose as the platform's six
    joints (position, then intrinsic yaw-pitch-roll), its dynamometers read where they are
    (``mjcf.topics``: ``cable_tensions: /cdpr/cable_tensions``), ``payload_body: platform``."""
    from scipy.spatial.transform import Rotation

    from ....bags import BagWriter, open_bag
    from ..sim import description_yaml

    src = open_bag(cdpr_bag)
    pose = src.pose("/cdpr/platform_pose")
    ten = src.joint_state("/cdpr/cable_tensions")
    angles = np.unwrap(Rotation.from_quat(pose.quaternion).as_euler("ZYX"), axis=0)
    desc = description_yaml(CAROCA.read_text(encoding="utf-8"), tendons=list(ten.names),
                            payload_body="platform", topics={"cable_tensions": "/cdpr/cable_tensions"})
    with BagWriter(out, overwrite=True) as w:
        w.write_description(desc, t=pose.t[0])
        w.write_joint_states("/mjcf/joint_states", pose.t, list(JOINTS),
                             position=np.column_stack([pose.position, angles]))
        w.write_joint_states("/cdpr/cable_tensions", ten.t, list(ten.names), effort=ten.effort)
    return str(out)


if __name__ == "__main__":
    import sys

    if len(sys.argv) == 3:                       # CDPR_BAG OUT: the bag for the mjcf plant
        print(mjcf_bag(sys.argv[1], sys.argv[2]))
    else:                                        # no argument: rewrite caroca.xml
        CAROCA.write_text(caroca_xml(), encoding="utf-8")
