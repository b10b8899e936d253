"""``base_tilt`` as two angles (002 sec. 6.5) against two oracles that are not its columns:
the potential of the horizontal gravity differentiated numerically through the crane kinematics,
and the MuJoCo crane on a tilted base holding still with the payload at its equilibrium."""
from __future__ import annotations

import mujoco
import numpy as np
import pytest
from scipy.optimize import root

from cablelab.description import load_description
from cablelab.dataset import Dataset
from cablelab.plants.crane import kinematics as kin
from cablelab.plants.crane import plant as C
from cablelab.plants.crane.effects import BASE_TILT, tilt_masses
from cablelab.plants.crane.model import CraneParams, gravity_vector, regressor
from cablelab.model import Model
from cablelab.plants.crane.mjcf import build_mjcf
from cablelab.plants.crane.sim import CraneTruth, gravity_in_base, set_state

DESC = load_description(C.__file__.replace("plant.py", "data/crane.yaml"))
P = CraneParams.from_description(DESC)


def _effect(q: np.ndarray, tilt_x: float, tilt_y: float) -> np.ndarray:
    """(N, 3) slew, luff, hoist contribution of base_tilt at the angles, through the registered effect."""
    ds = Dataset(plant="crane", t=np.arange(len(q), dtype=float), y=np.zeros((len(q), 3)),
                 channels=("slew", "luff", "hoist"), units=("N m", "N m", "N"),
                 signals={"q": q}, description=DESC)
    return BASE_TILT.regressor(ds) @ np.array([tilt_x, tilt_y])


def _horizontal_potential(q: np.ndarray, gx: float, gy: float) -> np.ndarray:
    """V = -(g_x, g_y) . sum_i m_i r_i over boom (centre l_b / 2), counterbalance (-l_c) and payload."""
    tip = kin.boom_tip(q[:, 0], q[:, 1], P.boom_length)
    pay = kin.payload_position(q[:, 0], q[:, 1], q[:, 2], q[:, 3], q[:, 4], P.boom_length)
    r = (P.boom_mass * 0.5 - P.counterbalance_mass * P.counterbalance_distance / P.boom_length) * tip \
        + P.payload_mass * pay
    return -(gx * r[:, 0] + gy * r[:, 1])


def test_tilt_masses_are_the_described_first_moment_and_payload():
    K, m, g = tilt_masses(DESC)
    assert K == pytest.approx(P.boom_length * (P.payload_mass + P.boom_mass / 2)
                              - P.counterbalance_distance * P.counterbalance_mass, rel=1e-12)
    assert (m, g) == (P.payload_mass, P.gravity)


def test_columns_are_the_gradient_of_the_horizontal_gravity_potential():
    """Effort to hold = dV/dq for slew, luff, hoist at random poses with swing (central differences
    of the kinematics' positions; g_x = g tilt_y, g_y = -g tilt_x)."""
    rng = np.random.default_rng(3)
    q = np.column_stack([rng.uniform(-3, 3, 20), rng.uniform(-0.2, 1.2, 20), rng.uniform(0.3, 1.5, 20),
                         rng.uniform(-0.3, 0.3, 20), rng.uniform(-0.3, 0.3, 20)])
    tx, ty = 0.031, -0.022
    gx, gy = P.gravity * ty, -P.gravity * tx
    h = 1e-6
    grad = np.empty((20, 3))
    for j in range(3):
        e = np.zeros(5)
        e[j] = h
        grad[:, j] = (_horizontal_potential(q + e, gx, gy) - _horizontal_potential(q - e, gx, gy)) / (2 * h)
    np.testing.assert_allclose(_effect(q, tx, ty), grad, atol=1e-7 * np.abs(grad).max())


def _held_at_rest(tilt, alpha, beta, d):
    """The MuJoCo crane on a base rotated by ``tilt`` at slew ``alpha``, luff ``beta``, rope
    ``d`` with the payload's swing angles at their equilibrium: (truth, swing angles, qfrc_bias)."""
    truth = CraneTruth(params=P, base_tilt=tilt)
    model = build_mjcf(truth)
    data = mujoco.MjData(model)

    def bias(sw):
        set_state(model, data, [alpha, beta, d, sw[0], sw[1]])
        return data.qfrc_bias.copy()

    sw = root(lambda s: bias(s)[2:4], [0.0, 0.0], tol=1e-14).x
    return truth, sw, bias(sw)


@pytest.mark.parametrize("tilt,alpha,beta", [((-0.04, 0.03), 0.0, 0.5), ((0.02, -0.05), 1.1, 0.2),
                                             ((0.035, 0.0), -2.3, 0.9)])
def test_mujoco_tilted_crane_at_rest_matches_the_angles(tilt, alpha, beta):
    """The MuJoCo crane on a base rotated by ``tilt`` (about world x, y), held at rest with the
    payload in its equilibrium: slew torque = the effect at tilt_x = -g_y / g, tilt_y = g_x / g
    exactly (the vertical gravity gives no slew torque); luff torque = vertical-gravity model +
    effect up to the second-order change of the vertical gravity."""
    d = 0.6
    truth, sw, b_all = _held_at_rest(tilt, alpha, beta, d)
    b = b_all
    assert np.abs(b[2:4]).max() < 1e-10
    g = gravity_in_base(truth)
    tx, ty = -g[1] / P.gravity, g[0] / P.gravity
    q = np.array([[alpha, beta, d, sw[0], sw[1]]])
    pred = gravity_vector(q, P)[0, :3] + _effect(q, tx, ty)[0]
    assert abs(b[0]) > 0.05                         # the tilt really loads the slew joint
    assert pred[0] == pytest.approx(b[0], abs=1e-9)
    second_order = (P.payload_mass + P.boom_mass + P.counterbalance_mass) * P.gravity * np.hypot(*tilt) ** 2
    assert abs(pred[1] - b[1]) < second_order
    # the untilted model misses the whole (first-order) slew torque
    assert abs(gravity_vector(q, P)[0, 0] - b[0]) > 100 * abs(pred[0] - b[0])


def test_free_run_truth_takes_the_fitted_angles():
    """The free-run simulator built from fitted parameters (freerun.truth_from_params) gets back the
    base rotation whose gravity the angles describe."""
    from cablelab.plants.crane.freerun import truth_from_params

    tilt = (0.045, -0.03)
    g = gravity_in_base(CraneTruth(params=P, base_tilt=tilt))
    truth = truth_from_params({"tilt_x": -g[1] / P.gravity, "tilt_y": g[0] / P.gravity}, DESC)
    np.testing.assert_allclose(truth.base_tilt, tilt, atol=1e-12)


def _model_at_rest(q: np.ndarray, tilt_x: float, tilt_y: float) -> np.ndarray:
    """(N, 3) efforts the crane model with ``base_tilt`` predicts at rest: every parameter at the
    description's value and the angles (Model.predict: the columns and the effect's higher-order
    term alike)."""
    z = np.zeros_like(q)
    ds = Dataset(plant="crane", t=np.arange(len(q), dtype=float), y=np.zeros((len(q), 3)),
                 channels=("slew", "luff", "hoist"), units=("N m", "N m", "N"),
                 signals={"q": q, "Y": regressor(q, z, z, P.gravity), "l_c": P.counterbalance_distance},
                 description=DESC)
    known = {"I_tot": P.slew_inertia, "I_b": P.luff_inertia, "m": P.payload_mass, "m_b": P.boom_mass,
             "m_c": P.counterbalance_mass, "l_c": P.counterbalance_distance}
    model = Model("crane", C.baseline(DESC) + ("base_tilt",), known)
    y, _ = model.predict(ds, {"tilt_x": tilt_x, "tilt_y": tilt_y})
    return y


@pytest.mark.parametrize("tilt,alpha,beta", [((-0.04, 0.03), 0.0, 0.5), ((0.05, 0.046), 1.1, 0.2),
                                             ((0.035, 0.0), -2.3, 0.9)])
def test_tilt_also_shortens_the_vertical_gravity(tilt, alpha, beta):
    """The tilted MuJoCo crane at rest holds exactly the untilted model with the vertical gravity
    g_z = g cos|tilt| plus the first-order columns: the columns alone over-predict the hoist force
    by m g (1 - cos|tilt|) ~ m g |tilt|^2 / 2 (0.1-0.3 % of the weight at 2-4 degrees, a constant
    a torque-sensor offset would take up), and the effect's higher-order term restores it: the
    model with base_tilt predicts the held efforts to round-off."""
    d = 0.6
    truth, sw, b_all = _held_at_rest(tilt, alpha, beta, d)
    b = b_all[[0, 1, 4]]                        # slew, luff, hoist dofs
    g = gravity_in_base(truth)
    tx, ty = -g[1] / P.gravity, g[0] / P.gravity
    q = np.array([[alpha, beta, d, sw[0], sw[1]]])
    first_order = gravity_vector(q, P)[0, :3] + _effect(q, tx, ty)[0]
    exact = gravity_vector(q, P)[0, :3] * abs(g[2]) / P.gravity + _effect(q, tx, ty)[0]
    np.testing.assert_allclose(b, exact, rtol=0, atol=1e-9 * P.payload_mass * P.gravity)
    shortfall = P.payload_mass * (P.gravity - abs(g[2]))
    assert abs(first_order[2] - b[2]) == pytest.approx(shortfall, rel=0.05)
    assert shortfall > 0.4 * P.payload_mass * P.gravity * np.hypot(*tilt) ** 2
    np.testing.assert_allclose(_model_at_rest(q, tx, ty)[0], b, rtol=0,
                               atol=1e-9 * P.payload_mass * P.gravity)
