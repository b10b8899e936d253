"""MuJoCo models of the cable-suspended platforms (spec 000_suspended.md sec. 3-4).

* :func:`virtual_xml` / :func:`build_virtual`: the virtual-joint open chain of 000 sec. 3
  (eq. 1-2, 5). Six hinges J7-J9 (top sphere at S) and J10-J12 (bottom sphere at distance L
  below J9), the passive PD of 000 eq. 2 as MuJoCo joint ``stiffness`` (target 0) + ``damping``,
  f_v as ``damping``, f_s as ``frictionloss``. LiCAS levelling (targets q11^d = -q8,
  q12^d = -q9, defect D5) either as a fixed tendon ``q8 + q11`` with stiffness k_p11
  (``levelling="tendon"``, conservative, works in ``mujoco.rollout``) or as motors on J11/J12
  whose ctrl the caller sets each step (``"paper"``, the repo Gazebo plugin; see
  :func:`levelling_ctrl`). Inconsistent cable-link inertias (D8) are fixed per spec sec. 4.2:
  the excess of an axis that breaks ``A + B >= C`` is moved to the armature of the cable joint
  turning about that axis (exact at q = 0).
* :func:`truth_xml` / :func:`build_truth`: physical truth plants. LiCAS: the platform is a free
  body hung by four length-limited spatial tendons (spec sec. 3.3) so swing and quadrifilar yaw
  return arise without virtual gains. CRANEbot: the virtual-joint model plus an axial rope
  spring-damper (``cable_elasticity``) between J9 and J10.

Arms: position servos (``kp``, ``kv``, force limits of the repo) on ``left_i`` / ``right_i``.
Output: site ``platform`` at the lower attachment point (J10-J12 origin), axes = platform axes.
Integrator ``implicitfast``, dt = 1 ms (000 sec. 5.3, spec 4.4).
"""
from __future__ import annotations

import mujoco
import numpy as np

from ...errors import CablelabError
from .params import VirtualParams, triangle_ok

__all__ = ["virtual_xml", "build_virtual", "truth_xml", "build_truth", "arm_joint_names",
           "levelling_ctrl", "effective_cable_inertias", "VJ", "AXES"]

VJ = ("J7", "J8", "J9", "J10", "J11", "J12")
#: hook body carrying S in the ``moving_suspension`` truth, kg, and its position-servo bandwidth, Hz
HOOK_MASS = 200.0
HOOK_BANDWIDTH_HZ = 5.0
#: LiCAS truth plant: side of the square of the four cables' attachment points, m (spec sec. 3.3)
CABLE_SEPARATION = 0.25
AXES = {"x": "1 0 0", "y": "0 1 0", "z": "0 0 1"}
_AXIS_IDX = {"x": 0, "y": 1, "z": 2}
#: cable joint turning about each axis (where an inertia excess goes as armature, spec 4.2)
_CABLE_JOINT_OF_AXIS = {0: "J8", 1: "J9", 2: "J7"}


def _f(x) -> str:
    return " ".join(repr(float(v)) for v in np.atleast_1d(x))


def arm_joint_names(p: VirtualParams) -> tuple[str, ...]:
    """``left_1..left_n, right_1..right_n`` (CONTRACT /suspended/joint_states order)."""
    n = p.n_arm
    return tuple(f"left_{i + 1}" for i in range(n)) + tuple(f"right_{i + 1}" for i in range(n))


def effective_cable_inertias(p: VirtualParams) -> tuple[list, dict]:
    """MuJoCo-valid inertia diagonals of links 7-9 and the armature they move to J7-J9.

    Link 7 turns only about z, so only its i_zz enters: diag(i_zz/2, i_zz/2, i_zz). On links 8
    and 9 an axis whose value exceeds the sum of the other two is lowered to that sum (x (1 - 1e-6))
    and the excess goes to the armature of the cable joint about that axis (spec sec. 4.2, D8);
    each axis is floored at 1e-5 kg m^2.

    Raises:
        CablelabError: ``inertia_fix="none"`` and a tensor breaks the triangle inequality.
    """
    diags = [np.array(p.I7, float), np.array(p.I8, float), np.array(p.I9, float)]
    if p.inertia_fix == "none":
        for k, d in zip((7, 8, 9), diags):
            if not triangle_ok(d):
                raise CablelabError(
                    f"suspended {p.variant}/{p.name}: link {k} inertia diag({_f(d)}) kg m^2 breaks "
                    "A + B >= C (defect D8, 000 Table 5); use inertia_fix='armature' (spec sec. 4.2)")
        return diags, {j: 0.0 for j in ("J7", "J8", "J9")}
    if p.inertia_fix != "armature":
        raise CablelabError(f"suspended inertia_fix: unknown value {p.inertia_fix!r} (armature | none)")
    arm = {"J7": 0.0, "J8": 0.0, "J9": 0.0}
    izz = max(diags[0][2], 2e-5)
    out = [np.array([izz / 2, izz / 2, izz])]
    for d in diags[1:]:
        d = np.maximum(d, 1e-5)            # MuJoCo needs > 0; 1e-5 kg m^2 floor
        ax = int(np.argmax(d))             # only the largest axis can break A + B >= C
        others = d.sum() - d[ax]
        if d[ax] > others:
            new = others * (1 - 1e-6)
            arm[_CABLE_JOINT_OF_AXIS[ax]] += d[ax] - new
            d[ax] = new
        out.append(d)
    return out, arm


def _arm_xml(p: VirtualParams, side: str, indent: str, frozen: bool = False) -> str:
    """Nested bodies of one arm (right mirrors y: positions, CoMs, ixy and iyz flip sign)."""
    s = 1.0 if side == "left" else -1.0
    mount = np.array(p.arm_mount) * [1, s, 1]
    parts, close = [], []
    for i, a in enumerate(p.arm):
        pos = mount if i == 0 else np.array(a.pos) * [1, s, 1]
        com = np.array(a.com) * [1, s, 1]
        ixx, iyy, izz, ixy, ixz, iyz = a.inertia
        fi = (ixx, iyy, izz, s * ixy, ixz, s * iyz)
        ind = indent + "  " * i
        parts.append(
            f'{ind}<body name="{side}_link{i + 1}" pos="{_f(pos)}">\n'
            + ("" if frozen else
               f'{ind}  <joint name="{side}_{i + 1}" axis="{AXES[a.axis]}" damping="{a.damping!r}"/>\n') +
            f'{ind}  <inertial pos="{_f(com)}" mass="{a.mass!r}" fullinertia="{_f(fi)}"/>')
        close.append(f"{ind}</body>")
    return "\n".join(parts + close[::-1])


def _actuators(p: VirtualParams, frozen: bool = False, motors: bool = False) -> str:
    lines = []
    if frozen:
        return ""
    for side in ("left", "right"):
        for i, a in enumerate(p.arm):
            if motors:   # torque inputs (N m) for an external controller, saturated at the limit
                lines.append(f'<motor name="{side}_{i + 1}" joint="{side}_{i + 1}" '
                             f'ctrlrange="{-a.effort!r} {a.effort!r}"/>')
                continue
            lines.append(f'<position name="{side}_{i + 1}" joint="{side}_{i + 1}" kp="{a.kp!r}" '
                         f'kv="{a.kd!r}" forcerange="{-a.effort!r} {a.effort!r}"/>')
    return "\n    ".join(lines)


def _option(timestep: float, integrator: str) -> str:
    return (f'<compiler angle="radian" autolimits="true"/>\n'
            f'  <option timestep="{timestep!r}" integrator="{integrator}" gravity="0 0 -9.81"/>')


#: the measured platform pose of every model (MJCF tail shared by the virtual and truth models)
_PLATFORM_SENSORS = """  <sensor>
    <framepos objtype="site" objname="platform"/>
    <framequat objtype="site" objname="platform"/>
  </sensor>
</mujoco>
"""


def virtual_xml(p: VirtualParams, *, levelling: str = "tendon", cable_elasticity=None,
                timestep: float = 1e-3, integrator: str = "implicitfast", lock=(),
                freeze_arms: bool = False, arm_motors: bool = False, moving_suspension: bool = False) -> str:
    """MJCF of the virtual-joint chain (module docstring).

    Args:
        p: parameter set. levelling: ``tendon`` | ``paper`` (LiCAS J11/J12 PD, spec 4.3).
        cable_elasticity: ``(k_c N/m, c_c N s/m)`` axial rope spring-damper (truth switch) or None.
        timestep: s. integrator: MuJoCo integrator name.
        lock: virtual joints left out (held at 0), e.g. ``("J7", "J9", "J10", "J12")`` for the
            planar reduction of spec 4.5. freeze_arms: arms rigid at q = 0 (no joints, no servos).
        arm_motors: arm torque motors (ctrl = N m) instead of the repo position servos.
        moving_suspension: truth switch for ``suspension_motion``: S sits on a heavy hook body
            (:data:`HOOK_MASS`) with horizontal slides ``hook_x``, ``hook_y`` driven by stiff
            position servos (actuators ``hook_x``, ``hook_y``, ctrl = displacement of S, m; the
            last two actuators). The realised S is the hook's qpos (a measured input).
    """
    lock = set(lock)
    if levelling not in ("tendon", "paper"):
        raise CablelabError(f"suspended levelling: unknown value {levelling!r} (tendon | paper)")
    (I7, I8, I9), armature = effective_cable_inertias(p)
    m7, m8, m9 = (max(float(v), 1e-4) for v in (p.m7, p.m8, p.m9))   # MuJoCo needs mass > 0 (1e-4 kg floor)
    fv, fs = p.fv, p.fs
    lvl_joint = p.level_to_swing and levelling == "tendon"
    lvl_pairs = [(n, a, b, k, c) for n, a, b, k, c in
                 (("level_x", "J8", "J11", p.kp11, p.kd11), ("level_y", "J9", "J12", p.kp12, p.kd12))
                 if a not in lock and b not in lock]
    # J11/J12 as plain stiffness (CRANEbot target 0) or via tendon / actuator (LiCAS)
    j11 = (f'stiffness="{p.kp11!r}" damping="{p.kd11!r}"' if not p.level_to_swing else "")
    j12 = (f'stiffness="{p.kp12!r}" damping="{p.kd12!r}"' if not p.level_to_swing else "")
    slide = ""
    if cable_elasticity is not None:
        kc, cc = (float(v) for v in cable_elasticity)
        slide = (f'<joint name="rope" type="slide" axis="0 0 1" stiffness="{kc!r}" damping="{cc!r}"/>')
    plat = (f'<inertial pos="{_f(p.c_plat)}" mass="{p.m_plat!r}" diaginertia="{_f(p.I_plat)}"/>')
    ind = " " * 16
    tendon = ""
    if lvl_joint:
        tendon = "<tendon>\n" + "\n".join(
            f'    <fixed name="{n}" stiffness="{k!r}" damping="{c!r}" springlength="0">'
            f'<joint joint="{a}" coef="1"/><joint joint="{b}" coef="1"/></fixed>'
            for n, a, b, k, c in lvl_pairs) + "\n  </tendon>"
    lvl_act = ""
    if p.level_to_swing and levelling == "paper":
        lvl_act = "\n    ".join(f'<motor name="level_{j}" joint="{j}"/>' for j in ("J11", "J12")
                                   if j not in lock)
    hook_open = hook_close = hook_act = ""
    link7_pos = _f(p.S)
    if moving_suspension:
        hook_open = (f'<body name="hook" pos="{_f(p.S)}">\n      <joint name="hook_x" type="slide" axis="1 0 0"/>'
                     f'<joint name="hook_y" type="slide" axis="0 1 0"/>'
                     f'<inertial pos="0 0 0" mass="{HOOK_MASS!r}" diaginertia="1 1 1"/>')
        hook_close = "</body>"
        link7_pos = "0 0 0"
        kp = float(HOOK_MASS * (2 * np.pi * HOOK_BANDWIDTH_HZ) ** 2)
        hook_act = "\n    ".join(f'<position name="{j}" joint="{j}" kp="{kp!r}" kv="{float(2 * np.sqrt(kp * HOOK_MASS))!r}"/>'
                                  for j in ("hook_x", "hook_y"))
    return f"""<mujoco model="suspended_{p.variant}_virtual">
  {_option(timestep, integrator)}
  <worldbody>
    {hook_open}
    <site name="S" pos="{"0 0 0" if moving_suspension else _f(p.S)}"/>
    <body name="link7" pos="{link7_pos}">
      {"" if "J7" in lock else f'<joint name="J7" axis="0 0 1" stiffness="{p.kp7!r}" damping="{p.kd7 + fv[0]!r}" frictionloss="{fs[0]!r}" armature="{float(armature["J7"])!r}"/>'}
      <inertial pos="0 0 {-p.l7z!r}" mass="{m7!r}" diaginertia="{_f(I7)}"/>
      <body name="link8">
        {"" if "J8" in lock else f'<joint name="J8" axis="1 0 0" damping="{fv[1]!r}" frictionloss="{fs[1]!r}" armature="{float(armature["J8"])!r}"/>'}
        <inertial pos="0 0 {-p.l8z!r}" mass="{m8!r}" diaginertia="{_f(I8)}"/>
        <body name="link9">
          {"" if "J9" in lock else f'<joint name="J9" axis="0 1 0" damping="{fv[2]!r}" frictionloss="{fs[2]!r}" armature="{float(armature["J9"])!r}"/>'}
          <inertial pos="0 0 {-p.l9z!r}" mass="{m9!r}" diaginertia="{_f(I9)}"/>
          <body name="link10" pos="0 0 {-p.L!r}">
            {slide}
            {"" if "J10" in lock else f'<joint name="J10" axis="0 0 1" stiffness="{p.kp10!r}" damping="{p.kd10!r}"/>'}
            {plat}
            <body name="link11">
              {"" if "J11" in lock else f'<joint name="J11" axis="1 0 0" {j11}/>'}
              {plat}
              <body name="platform">
                {"" if "J12" in lock else f'<joint name="J12" axis="0 1 0" {j12}/>'}
                {plat}
                <site name="platform"/>
{_arm_xml(p, "left", ind, freeze_arms)}
{_arm_xml(p, "right", ind, freeze_arms)}
              </body>
            </body>
          </body>
        </body>
      </body>
    </body>
    {hook_close}
  </worldbody>
  {tendon}
  <actuator>
    {_actuators(p, freeze_arms, arm_motors)}
    {lvl_act}
    {hook_act}
  </actuator>
{_PLATFORM_SENSORS}"""


def build_virtual(p: VirtualParams, **kw) -> mujoco.MjModel:
    """Compiled virtual-joint model (see :func:`virtual_xml` for the keywords)."""
    return mujoco.MjModel.from_xml_string(virtual_xml(p, **kw))


def levelling_ctrl(p: VirtualParams, qpos_J, qvel_J) -> np.ndarray:
    """Paper levelling torques on J11, J12 (repo ShouldersControlPlugin, D5):
    ``k_p11 (-q8 - q11) + k_d11 (-qd8 - qd11)`` and the same with q9, q12.

    Args:
        qpos_J, qvel_J: (..., 6) virtual joint positions / velocities J7..J12.
    """
    q, qd = np.asarray(qpos_J), np.asarray(qvel_J)
    return np.stack([p.kp11 * (-q[..., 1] - q[..., 4]) + p.kd11 * (-qd[..., 1] - qd[..., 4]),
                     p.kp12 * (-q[..., 2] - q[..., 5]) + p.kd12 * (-qd[..., 2] - qd[..., 5])], -1)


def truth_xml(p: VirtualParams, *, platform_mass: float = 0.7, cable_separation: float = CABLE_SEPARATION,
              timestep: float = 1e-3, integrator: str = "implicitfast", cable_elasticity=None,
              arm_motors: bool = False) -> str:
    """MJCF of the physical truth plant.

    LiCAS: free platform (``platform_mass`` kg, inertia I10 of 000 Table 3) with the arms, hung by
    four spatial tendons ``limited range 0..L`` from top sites at S + (+-s/2, +-s/2, 0) to platform
    sites (+-s/2, +-s/2, 0) (spec sec. 3.3). CRANEbot: the virtual-joint model with an axial rope
    spring-damper (default k_c = 2e5 N/m, c_c = 2e3 N s/m).

    Args:
        arm_motors: arms driven by torque motors (ctrl = N m, for :mod:`.control`) instead of
            the repo position servos.
    """
    if p.variant == "cranebot":
        return virtual_xml(p, cable_elasticity=cable_elasticity or (2e5, 2e3), timestep=timestep,
                           integrator=integrator)
    h = cable_separation / 2
    corners = [(sx * h, sy * h) for sx, sy in ((1, 1), (-1, 1), (-1, -1), (1, -1))]
    S = np.array(p.S, float)
    top = "\n    ".join(f'<site name="top{i}" pos="{_f(S + [x, y, 0])}"/>' for i, (x, y) in enumerate(corners))
    bot = "\n        ".join(f'<site name="bot{i}" pos="{_f([x, y, 0])}"/>' for i, (x, y) in enumerate(corners))
    tend = "\n    ".join(
        f'<spatial name="cable{i}" limited="true" range="0 {p.L!r}" solreflimit="0.004 1" width="0.003">'
        f'<site site="top{i}"/><site site="bot{i}"/></spatial>' for i in range(4))
    ind = " " * 8
    start = S - [0, 0, p.L]
    return f"""<mujoco model="suspended_{p.variant}_truth">
  {_option(timestep, integrator)}
  <worldbody>
    <site name="S" pos="{_f(S)}"/>
    {top}
    <body name="platform" pos="{_f(start)}">
      <freejoint name="platform_free"/>
      <inertial pos="0 0 0" mass="{platform_mass!r}" diaginertia="{_f(p.I_plat)}"/>
      <site name="platform"/>
        {bot}
{_arm_xml(p, "left", ind)}
{_arm_xml(p, "right", ind)}
    </body>
  </worldbody>
  <tendon>
    {tend}
  </tendon>
  <actuator>
    {_actuators(p, motors=arm_motors)}
  </actuator>
{_PLATFORM_SENSORS}"""


def build_truth(p: VirtualParams, **kw) -> mujoco.MjModel:
    """Compiled truth plant (see :func:`truth_xml`)."""
    return mujoco.MjModel.from_xml_string(truth_xml(p, **kw))
