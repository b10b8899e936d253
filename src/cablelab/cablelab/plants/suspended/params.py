"""Parameter sets of the cable-suspended dual-arm platforms (paper 000, spec 000_suspended.md).

Two variants, ``licas`` and ``cranebot``, each with two sets:

* ``repo`` (default): the public repo ``prisma-lab/cable-suspended-robots`` values with the
  paper's defects resolved as spec sec. 2.5 says (D2: CRANEbot k_p,10 = 551.3; D3: LiCAS 0.639 kg
  on each platform link; D6: CRANEbot cable mass 35.55 kg over links 7-9) and the cable-link
  inertias made physical by the armature workaround of spec sec. 4.2 (D8).
* ``table5``: 000 Table 5 verbatim (CRANEbot k_p,10 = 0.041, m8 = m9 = 35.55 kg), cable-link
  inertias verbatim. They break the triangle inequality (D8), so building it fails with a
  one-line error naming D8 unless ``inertia_fix="armature"`` is chosen explicitly.

All values SI: kg, m, kg m^2, N m/rad, N m s/rad, N m.
"""
from __future__ import annotations

import dataclasses
from dataclasses import dataclass, field

from ...errors import CablelabError

__all__ = ["ArmLink", "VirtualParams", "parameter_set", "VARIANTS", "SETS", "VIRTUAL_JOINTS",
           "IDENTIFIED"]

VARIANTS = ("licas", "cranebot")
SETS = ("repo", "table5")
#: the six virtual joints of 000 sec. 3 (J7-J9 top sphere, J10-J12 bottom sphere) and their axes
VIRTUAL_JOINTS = (("J7", "z"), ("J8", "x"), ("J9", "y"), ("J10", "z"), ("J11", "x"), ("J12", "y"))


@dataclass(frozen=True)
class ArmLink:
    """One arm link (left arm; the right arm mirrors y).

    Args:
        pos: joint origin in the parent link frame, m.
        axis: joint axis ``"x"``, ``"y"`` or ``"z"``.
        mass: kg. com: centre of mass in the link frame, m.
        inertia: (ixx, iyy, izz, ixy, ixz, iyz) about the CoM, kg m^2.
        kp, kd: joint PD gains (N m/rad, N m s/rad). effort: torque limit, N m.
        damping: joint viscous friction, N m s/rad.
    """

    pos: tuple
    axis: str
    mass: float
    com: tuple
    inertia: tuple
    kp: float
    kd: float
    effort: float
    damping: float = 0.0


@dataclass(frozen=True)
class VirtualParams:
    """Virtual-joint model parameters (000 Table 5 rows, repo yaml gains).

    Args:
        variant: ``licas`` or ``cranebot``. name: parameter-set name.
        L: cable length J9 -> J10, m. S: suspension point in world, m.
        m7, m8, m9: cable link masses, kg. l7z, l8z, l9z: cable link CoM depth below the joint, m.
        I7, I8, I9: cable link inertia diagonals (xx, yy, zz) as given by the source, kg m^2.
        fv: (3,) viscous friction J7-J9, N m s/rad. fs: (3,) Coulomb friction J7-J9, N m.
        kp7, kd7, kp10, kd10, kp11, kd11, kp12, kd12: virtual PD gains (000 eq. 2).
        m_plat: mass on each of the links 10-12, kg. c_plat: their CoM in the link frame, m.
        I_plat: inertia diagonal of each platform link, kg m^2.
        arm_mount: first arm joint of the left arm in the platform frame, m.
        arm: left arm links (right mirrors y).
        level_to_swing: LiCAS levelling targets q11^d = -q8, q12^d = -q9 (D5); False: target 0.
        inertia_fix: ``"armature"`` (spec sec. 4.2) or ``"none"`` (verbatim; fails D8 if invalid).
    """

    variant: str
    name: str
    L: float
    S: tuple
    m7: float
    m8: float
    m9: float
    l7z: float
    l8z: float
    l9z: float
    I7: tuple
    I8: tuple
    I9: tuple
    fv: tuple
    fs: tuple
    kp7: float
    kd7: float
    kp10: float
    kd10: float
    kp11: float
    kd11: float
    kp12: float
    kd12: float
    m_plat: float
    c_plat: tuple
    I_plat: tuple
    arm_mount: tuple
    arm: tuple = field(default=())
    level_to_swing: bool = True
    inertia_fix: str = "armature"

    def replace(self, **kw) -> "VirtualParams":
        """A copy with some fields changed (``p.replace(kp10=0.041)``)."""
        return dataclasses.replace(self, **kw)

    @property
    def n_arm(self) -> int:
        return len(self.arm)


#: the identified (★) parameters of 000 Table 5 as (name, LiCAS (p_0, p̄), CRANEbot (p_0, p̄))
IDENTIFIED = (
    ("m8", (1.0, 10.0), (30.0, 45.0)), ("m9", (1.0, 10.0), (30.0, 45.0)),
    ("l8z", (0.1, 1.0), (0.1, 3.5)), ("l9z", (0.1, 1.0), (0.1, 3.5)),
    ("ixx", (0.0, 2.0), (0.0, 100.0)), ("iyy", (0.0, 2.0), (0.0, 100.0)),
    ("izz", (0.8, 5.0), (0.0, 100.0)),
    ("fv7", (0.2, 2.0), (0.2, 2.0)), ("fv8", (0.1, 3.0), (1.0, 600.0)),
    ("fv9", (0.1, 3.0), (50.0, 100.0)),
    ("fs7", (0.0, 1.0), (0.0, 1.0)), ("fs8", (0.0, 1.0), (0.0, 1.0)), ("fs9", (0.0, 1.0), (0.0, 1.0)),
    ("kd7", (1.0, 5.0), (1.0, 5.0)), ("kp7", (15.0, 50.0), (40.0, 50.0)),
    ("kd10", (1.0, 5.0), (1.0, 5.0)), ("kp10", (10.0, 50.0), (1.0, 50.0)),
    ("kd11", (1.0, 5.0), (1.0, 5.0)), ("kp11", (100.0, 1000.0), (100.0, 1000.0)),
    ("kd12", (1.0, 5.0), (1.0, 5.0)), ("kp12", (100.0, 1000.0), (100.0, 1000.0)),
)

# --------------------------------------------------------------------------- LiCAS (spec 2.2)
_LICAS_ARM = (
    # repo urdf/licasa1.urdf.xacro: offsets, axes y x z y, masses (= Table 5), CoMs, inertias;
    # gains config/licasa1_controllers.yaml; effort 10 N m (D1: Table 3 arm rows not used)
    ArmLink((0.0, 0.0, 0.0), "y", 0.233, (0.0, 0.0236, -0.00946),
            (3.68e-4, 1.16e-4, 3.76e-4, -7.57e-6, 5.38e-6, -4.8e-5), 200.0, 0.55, 10.0),
    ArmLink((0.0, 0.04, 0.0), "x", 0.246, (-0.015, 0.0, -0.1),
            (3.49e-4, 4.46e-4, 1.49e-4, 0.0, -3.79e-5, 0.0), 50.0, 0.5, 10.0),
    ArmLink((0.0, 0.0, -0.143), "z", 0.214, (0.0, 0.0, -0.093),
            (4.21e-4, 4.26e-4, 5.01e-5, -7.81e-7, -4.06e-5, 1.8e-5), 1.5, 0.1, 10.0),
    ArmLink((0.0, 0.0, -0.132), "y", 0.106, (0.0, 0.0, -0.092),
            (3.94e-4, 3.75e-4, 3.05e-5, 0.0, 0.0, -3.5e-6), 50.0, 0.55, 10.0),
)

_LICAS_REPO = VirtualParams(
    variant="licas", name="repo", L=1.0, S=(0.0, 0.0, 1.85),
    m7=1.0, m8=4.237, m9=5.032, l7z=0.0, l8z=0.174, l9z=0.824,
    # Table 5 i_xx, i_yy, i_zz for links 7-9 (one value per axis, same on each link)
    I7=(0.313, 0.363, 0.745), I8=(0.313, 0.363, 0.745), I9=(0.313, 0.363, 0.745),
    fv=(0.517, 1.33, 1.311), fs=(0.0, 0.0, 0.0),
    kp7=17.855, kd7=0.0, kp10=0.021, kd10=0.556, kp11=682.4, kd11=0.01, kp12=712.3, kd12=0.01,
    m_plat=0.639, c_plat=(0.0, 0.0, 0.0), I_plat=(3.02e-3, 8.64e-4, 3.39e-3),
    arm_mount=(0.0, 0.14, 0.0), arm=_LICAS_ARM, level_to_swing=True, inertia_fix="armature")

_LICAS_TABLE5 = _LICAS_REPO.replace(name="table5", kp7=17.86, inertia_fix="none")

# --------------------------------------------------------------------------- CRANEbot (spec 2.3)
# Pilz PRBT arms as a simplified chain hanging below the platform (z y y z y z axes, link lengths
# L0..L3 of the repo along -z). The repo rpy frames are NOT reproduced: the CoMs are the repo
# vectors in these simplified frames (lumped arms, enough for A1/A3 per the spec).
_T4 = {13: (3.53e-2, 3.01e-2, 1.87e-2, 0.0, 0.0, 9.04e-3),
       15: (3.58e-2, 3.22e-3, 3.66e-2, 0.0, 0.0, -1.45e-3),
       17: (2.06e-2, 1.08e-2, 1.63e-2, 0.0, 0.0, -5.36e-3),
       19: (6.79e-3, 4.91e-3, 3.40e-3, 0.0, 0.0, 2.67e-3),
       21: (7.37e-3, 5.87e-3, 3.96e-3, 0.0, 0.0, -1.71e-3),
       23: (1e-5, 1e-5, 1e-5, 0.0, 0.0, 0.0)}   # Table 4 gives 0; MuJoCo needs > 0 (1e-5 kg m^2)
_CRANEBOT_ARM = (
    ArmLink((0.0, 0.0, 0.0), "z", 7.1, (0.0, -0.026, -0.051), _T4[13], 5000.0, 0.0, 370.0, 15.0),
    ArmLink((0.0, 0.0, -0.2604), "y", 1.7, (0.0, 0.0, -0.162), _T4[15], 16000.0, 25.0, 370.0, 12.0),
    ArmLink((0.0, 0.0, -0.35), "y", 4.8, (0.0, 0.043, -0.027), _T4[17], 5000.0, 0.0, 176.0, 4.5),
    ArmLink((0.0, 0.0, -0.05), "z", 0.9, (0.0, 0.0, -0.204), _T4[19], 5000.0, 0.0, 176.0, 4.2),
    ArmLink((0.0, 0.0, -0.307), "y", 2.6, (-0.001, 0.021, -0.032), _T4[21], 5000.0, 0.0, 41.6, 1.5),
    ArmLink((0.0, 0.0, -0.084), "z", 0.2, (0.0, 0.0, 0.0), _T4[23], 5000.0, 0.0, 20.1, 4.5),
)

_CRANEBOT_REPO = VirtualParams(
    variant="cranebot", name="repo", L=3.357 + 0.126, S=(0.0, 1.01, 6.0 - 0.159),
    # D6: repo massCablesPulley = 35.55 kg over links 7-9
    m7=35.55 / 3, m8=35.55 / 3, m9=35.55 / 3, l7z=1.894, l8z=1.894, l9z=1.894,
    I7=(1.0, 1.0, 5.807), I8=(35.37, 1.0, 1e-3), I9=(1.0, 58.23, 1e-3),
    fv=(0.9, 485.3, 52.7), fs=(0.01, 0.767, 0.0),
    # D2: repo yaml k_p,10 = 551.3 (Table 5: 0.041)
    kp7=30.927, kd7=0.0, kp10=551.3, kd10=0.0, kp11=953.2, kd11=0.0, kp12=891.5, kd12=0.0,
    m_plat=156.25 / 3, c_plat=(0.0, 0.0, -0.521), I_plat=(1.0, 1.0, 1e-3),
    arm_mount=(0.0, 0.19, -1.1024), arm=_CRANEBOT_ARM, level_to_swing=False, inertia_fix="armature")

_CRANEBOT_TABLE5 = _CRANEBOT_REPO.replace(
    name="table5", m8=35.55, m9=35.55, kp7=30.92, kp10=0.041, inertia_fix="none")

_SETS = {("licas", "repo"): _LICAS_REPO, ("licas", "table5"): _LICAS_TABLE5,
         ("cranebot", "repo"): _CRANEBOT_REPO, ("cranebot", "table5"): _CRANEBOT_TABLE5}


def parameter_set(variant: str = "licas", name: str = "repo") -> VirtualParams:
    """The named parameter set of a variant.

    Raises:
        CablelabError: unknown variant or set name (one line naming it).
    """
    if variant not in VARIANTS:
        raise CablelabError(f"suspended.variant: unknown variant {variant!r} (expected one of "
                            f"{', '.join(VARIANTS)})")
    if name not in SETS:
        raise CablelabError(f"suspended parameter set {name!r} unknown (expected one of {', '.join(SETS)})")
    return _SETS[(variant, name)]


def triangle_ok(diag) -> bool:
    """True if a principal-inertia triple satisfies A + B >= C for every permutation."""
    a, b, c = (float(v) for v in diag)
    return a + b >= c and a + c >= b and b + c >= a and min(a, b, c) >= 0
