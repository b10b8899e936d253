"""Effects of the boom crane (002): the rigid body, the counterbalance and the tilted base.

The crane dataset (:mod:`cablelab.plants.crane`) carries the signal ``Y`` (N, 5, 9), the
regressor of 002 eq. 4.1-4.2 generated from the energies A.3-A.4; the output channels are its
three actuated rows (slew torque N m, luff torque N m, hoist force N). The boom length l_b is
known (description ``crane.boom_length``), so the groups of 002 eq. 4.2 collapse onto physical
parameters:

* ``crane_rigid_body``: I_tot, I_b (kg m^2), payload mass m and boom mass m_b (kg), columns
  ``Y_Itot``, ``Y_Ib``, ``l_b^2 Y_lb2m + l_b Y_lbm + Y_m`` and ``l_b^2 Y_lb2mb + l_b Y_lbmb``.
* ``counterbalance``: point mass m_c (linear) at distance l_c (nonlinear, searched by the
  separable least squares) behind the luff pivot (002 sec. 3.1, 6.4): ``l_c^2 Y_lc2mc + l_c Y_lcmc``.
  With m_b free, (m_b, m_c, l_c) has one unidentifiable direction (002 sec. 5.3.2: rank 6):
  fix m_b or l_c (``--fix``) to read m_c and l_c; the fit itself is unaffected.
* ``base_tilt``: the slew axis tilted from the vertical (002 sec. 6.5), parameters the two small
  rotations of the base about world x and y, ``tilt_x``, ``tilt_y`` (rad; exactly -g_y / g and
  g_x / g of gravity in the base frame, the first-order tilt angles). Gravity in the base frame
  then has horizontal components (g_x, g_y) = g (tilt_y, -tilt_x); the weight of the boom side
  (moment K = l_b m + l_b m_b/2 - l_c m_c) and of the swinging payload load the slew joint (and
  luff, hoist), see :func:`tilt_columns`: ``slew = cos(beta) (K g_x sin(alpha) - K g_y cos(alpha))
  + payload terms``. K and m are the KNOWN masses of the description (:func:`tilt_masses`): the
  tilt is two angles, not four free loads, because the payload's load ``m g_x`` alone is barely
  excited (swing angles of a few degrees) and as a free parameter it carried 10-20 % standard
  errors on the diagnosis benchmark (bench/cases_crane.py). At rest it is the slew torque offset
  002 measured (-0.2 N m). The columns are first order in the angles; the tilt also shortens the
  vertical gravity to g cos|tilt| (:func:`tilt_vertical_shortening`, a constant m g |tilt|^2 / 2
  on the hoist that a torque-sensor offset would otherwise take up), the effect's higher-order
  term, which the fit evaluates at its current angles and iterates
  (:attr:`~cablelab.effects.base.Effect.higher_order`): the output is exact in the angles
  (tested against the tilted MuJoCo crane at rest).
"""
from __future__ import annotations

from typing import Mapping

import numpy as np

from ...dataset import Dataset
from ...effects.base import Effect, Param
from .model import PARAM_GROUPS
from ...effects import register

#: columns of the 9 groups of 002 eq. 4.2 in the generated regressor (its PARAM_GROUPS order)
I_TOT, LB2_MB, LB2_M, LB_M, M, LB_MB, I_B, LC2_MC, LC_MC = (PARAM_GROUPS.index(g) for g in (
    "I_tot", "lb2_mb", "lb2_m", "lb_m", "m", "lb_mb", "I_b", "lc2_mc", "lc_mc"))
#: default and search range of the counterbalance distance l_c, m
LC_NOMINAL, LC_BOUNDS = 0.3, (0.02, 2.0)


def _boom_length(ds: Dataset) -> float:
    desc = ds.description
    if desc is not None and getattr(desc, "crane", None) is not None:
        return float(desc.crane.boom_length)
    return float(ds.require_signal("boom_length"))


def _rigid(ds: Dataset) -> np.ndarray:
    Y = ds.require_signal("Y")[:, :3, :]
    lb = _boom_length(ds)
    return np.stack([Y[:, :, I_TOT], Y[:, :, I_B],
                     lb * lb * Y[:, :, LB2_M] + lb * Y[:, :, LB_M] + Y[:, :, M],
                     lb * lb * Y[:, :, LB2_MB] + lb * Y[:, :, LB_MB]], axis=2)


def _cb_transform(ds: Dataset, values: Mapping[str, float]) -> Dataset:
    return ds.replace(signals={**ds.signals, "l_c": float(values.get("l_c", LC_NOMINAL))})


def _cb(ds: Dataset) -> np.ndarray:
    Y = ds.require_signal("Y")[:, :3, :]
    lc = float(ds.signals.get("l_c", LC_NOMINAL))
    return (lc * lc * Y[:, :, LC2_MC] + lc * Y[:, :, LC_MC])[:, :, None]


def tilt_columns(q: np.ndarray) -> np.ndarray:
    """(N, 3, 4) base-tilt regressor for q (N, 5) [alpha, beta, d, theta1, theta2].

    Parameters [K g_x, K g_y, m g_x, m g_y]: the horizontal gravity components (g_x, g_y) of the
    tilted base frame times the boom-side moment K and the payload mass m. Potential
    ``-(g_x, g_y) . (K cos(beta) [cos a, sin a] + m d Rz(alpha) [sin th2, sin th1 cos th2])``
    (exact to first order in the tilt); the columns are its partial derivatives.
    """
    q = np.asarray(q, dtype=float)
    ca, sa, cb, sb = np.cos(q[:, 0]), np.sin(q[:, 0]), np.cos(q[:, 1]), np.sin(q[:, 1])
    d = q[:, 2]
    w1 = np.sin(q[:, 4])
    w2 = np.sin(q[:, 3]) * np.cos(q[:, 4])
    ux, uy = ca * w1 - sa * w2, sa * w1 + ca * w2           # Rz(alpha) w
    dux, duy = -sa * w1 - ca * w2, ca * w1 - sa * w2        # d/dalpha
    out = np.zeros((q.shape[0], 3, 4))
    out[:, 0, 0], out[:, 0, 1] = cb * sa, -cb * ca
    out[:, 1, 0], out[:, 1, 1] = sb * ca, sb * sa
    out[:, 0, 2], out[:, 0, 3] = -d * dux, -d * duy
    out[:, 2, 2], out[:, 2, 3] = -ux, -uy
    return out


CRANE_RIGID_BODY = register(Effect(
    id="crane_rigid_body",
    plants=("crane",),
    params=(Param("I_tot", "kg m^2", 0.0, 0.0, np.inf, "slew inertia of the turret about z"),
            Param("I_b", "kg m^2", 0.0, 0.0, np.inf, "luff inertia of the boom (beyond its point mass)"),
            Param("m", "kg", 0.0, 0.0, np.inf, "payload mass"),
            Param("m_b", "kg", 0.0, 0.0, np.inf, "boom mass (uniform boom, centre at l_b / 2)")),
    explanation="boom, payload pendulum and turret inertia and gravity (Lagrange, 002 eq. A.7-A.11)",
    signature="residual follows the accelerations and cos(beta)",
    reference="002 eq. 3.5, 4.1-4.2",
    regressor=_rigid,
))

COUNTERBALANCE = register(Effect(
    id="counterbalance",
    plants=("crane",),
    params=(Param("m_c", "kg", 0.0, 0.0, np.inf, "counterbalance mass"),),
    nonlinear=(Param("l_c", "m", LC_NOMINAL, LC_BOUNDS[0], LC_BOUNDS[1],
                     "counterbalance distance behind the luff pivot"),),
    transform=_cb_transform,
    explanation="a point mass m_c at l_c behind the luff pivot lowers the luff gravity torque and "
                "adds slew/luff inertia",
    signature="luff torque residual follows cos(beta); slew residual follows cos^2(beta) alpha_ddot",
    reference="002 sec. 3.1, 6.4",
    regressor=_cb,
))


def tilt_masses(desc) -> tuple[float, float, float]:
    """(K kg m, m kg, g m/s^2) that scale the base tilt: the boom-side first moment
    K = l_b m + l_b m_b / 2 - l_c m_c and the payload mass m of the description (missing masses:
    :class:`CraneParams` defaults; no counterbalance: m_c = 0). The description's, not the fitted
    ones: the regressor must not change between the fit and the prediction (a weighed payload and
    the described boom are what a tilt calibration uses; a wrong described K scales the angles)."""
    from .model import CraneParams

    p = CraneParams.from_description(desc) if desc is not None else CraneParams()
    return p.first_moment, p.payload_mass, p.gravity


def tilt_angle_columns(q: np.ndarray, first_moment: float, payload_mass: float,
                       gravity: float = 9.81) -> np.ndarray:
    """(N, 3, 2) base-tilt regressor in the angles [tilt_x, tilt_y] (rad, rotation of the base
    about world x, y): g_x = g tilt_y, g_y = -g tilt_x in :func:`tilt_columns` weighted by K and m.
    First order in the angles: the tilt also shortens the vertical gravity to g cos|tilt|, which
    these columns leave out (a constant m g |tilt|^2 / 2 on the hoist, 0.1-0.3 % of the weight at
    2-4 degrees) and :func:`tilt_vertical_shortening` adds; without it a fit whose residual is
    clean enough (efforts and columns parallel-filtered) sees a significant hoist offset."""
    c = tilt_columns(q)
    gx = first_moment * c[:, :, 0] + payload_mass * c[:, :, 2]     # per unit g_x
    gy = first_moment * c[:, :, 1] + payload_mass * c[:, :, 3]     # per unit g_y
    return gravity * np.stack([-gy, gx], axis=2)


def _tilt(ds: Dataset) -> np.ndarray:
    K, m, g = tilt_masses(ds.description)
    return tilt_angle_columns(ds.require_signal("q"), K, m, g)


def tilt_vertical_shortening(q: np.ndarray, tilt_x: float, tilt_y: float, params) -> np.ndarray:
    """(N, 3) slew, luff, hoist change of the vertical-gravity efforts on a base tilted by
    (tilt_x, tilt_y): gravity along the slew axis is g_z = g sqrt(1 - tilt_x^2 - tilt_y^2)
    = g cos|tilt| (exactly, with tilt_x = -g_y / g and tilt_y = g_x / g), so the vertical
    gravity vector G(q) of :class:`CraneParams` ``params`` scales by cos|tilt|: ``(cos|tilt|
    - 1) G(q)``, about -|tilt|^2 / 2 G(q) (the slew row is 0: vertical gravity loads no slew
    torque)."""
    from .model import gravity_vector

    cos_tilt = np.sqrt(max(0.0, 1.0 - float(tilt_x) ** 2 - float(tilt_y) ** 2))
    return (cos_tilt - 1.0) * gravity_vector(q, params)[:, :3]


def _tilt_higher_order(ds: Dataset, values: Mapping[str, float]) -> np.ndarray:
    from .model import CraneParams

    tx, ty = float(values.get("tilt_x", 0.0)), float(values.get("tilt_y", 0.0))
    q = ds.require_signal("q")
    if tx == 0.0 and ty == 0.0:
        return np.zeros((q.shape[0], 3))
    desc = ds.description
    return tilt_vertical_shortening(q, tx, ty, CraneParams.from_description(desc)
                                    if desc is not None else CraneParams())


BASE_TILT = register(Effect(
    id="base_tilt",
    plants=("crane",),
    params=(Param("tilt_x", "rad", 0.0, -np.inf, np.inf,
                  "base rotation about world x (= -g_y / g in the base frame)"),
            Param("tilt_y", "rad", 0.0, -np.inf, np.inf,
                  "base rotation about world y (= g_x / g in the base frame)")),
    explanation="the slew axis is not vertical, so the weight of the boom side loads the slew "
                "joint with a torque that depends on the slew angle",
    signature="slew torque offset at rest that changes with alpha like cos/sin(alpha)",
    reference="002 sec. 6.5 (-0.2 N m at rest); K, m: the described masses",
    regressor=_tilt,
    higher_order=_tilt_higher_order,
))
