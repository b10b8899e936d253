"""The mjcf plant's regressor columns against independent oracles: a model that MuJoCo's own
model editor (MjSpec) compiled with the change, not the column code's runtime edits."""
import numpy as np
import pytest
from hypothesis import given, settings, strategies as st

import mujoco

from cablelab.plants.mjcf.inverse import (body_columns, inverse_dynamics, inverse_record,
                                          point_mass_columns, set_standard_params, standard_params)
from cablelab.plants.mjcf.mjcf import load_model
from cablelab.plants.mjcf.sim import Hidden, truth_model

from cablelab.plants.mjcf.examples import ARM3, CABLECAM, GANTRY, text

ARM_XML = text(ARM3)

RNG = np.random.default_rng(0)
Q, QD, QDD = RNG.normal(size=(3, 60, 3))
TOOL = 4


@pytest.fixture(scope="module")
def tool_columns():
    model, _ = load_model(ARM_XML)
    cols = body_columns(model, inverse_record(model, Q, QD, QDD), TOOL)
    return model, inverse_dynamics(model, Q, QD, QDD), cols


_INERTIAL_FIELDS = ("body_mass", "body_ipos", "body_inertia", "body_iquat", "body_sameframe")


def _difference_columns(model, body, q, qd, qdd, step=1e-3):
    """The oracle: ``(tau(theta + step e_k) - tau(theta)) / step`` of ``mj_inverse`` with the
    body's standard parameters written into the model (exact up to round-off: tau is linear in
    them); the model is restored."""
    theta0 = standard_params(model, body)
    saved = [np.array(getattr(model, f)[body]) for f in _INERTIAL_FIELDS]
    tau0 = inverse_dynamics(model, q, qd, qdd)
    cols = np.empty(tau0.shape + (10,))
    try:
        for k in range(10):
            th = theta0.copy()
            th[k] += step
            set_standard_params(model, body, th)
            cols[:, :, k] = (inverse_dynamics(model, q, qd, qdd) - tau0) / step
    finally:
        for f, v in zip(_INERTIAL_FIELDS, saved):
            getattr(model, f)[body] = v
    return cols


def _arm_with_gravcomp():
    """ARM3 with gravity compensation on the upper arm, routed to the shoulder's actuator."""
    spec = mujoco.MjSpec.from_string(ARM_XML)
    spec.body("upper").gravcomp = 0.4
    spec.joint("shoulder").actgravcomp = True
    spec.body("fore").gravcomp = 1.0
    return spec.compile()


@pytest.mark.parametrize("make", [lambda: load_model(text(ARM3))[0], lambda: load_model(text(GANTRY))[0],
                                  lambda: load_model(text(CABLECAM))[0], _arm_with_gravcomp],
                         ids=["arm3", "gantry", "cablecam", "arm3_gravcomp"])
def test_body_columns_of_one_pass_equal_the_differences_of_mj_inverse(make):
    """Every moving body's ten columns from one inverse pass (MuJoCo's cdof, cvel, cacc) equal
    the differences of mj_inverse with the parameters edited, on random states."""
    model = make()
    rng = np.random.default_rng(3)
    q, qd, qdd = rng.normal(size=(3, 40, model.nv))
    rec = inverse_record(model, q, qd, qdd)
    np.testing.assert_array_equal(rec.tau, inverse_dynamics(model, q, qd, qdd))
    for b in range(1, model.nbody):
        if model.body_weldid[b] == 0:
            continue
        oracle = _difference_columns(model, b, q, qd, qdd)
        np.testing.assert_allclose(body_columns(model, rec, b), oracle,
                                   atol=1e-8 * (1.0 + np.abs(oracle).max()), err_msg=f"body {b}")


def _with_point_mass(mass, pos):
    spec = mujoco.MjSpec.from_string(ARM_XML)
    b = spec.body("tool").add_body(name="pm", pos=list(pos))
    b.ipos, b.mass, b.inertia, b.explicitinertial = [0, 0, 0], mass, [1e-12] * 3, True
    return spec.compile()


@settings(max_examples=15, deadline=None)
@given(mass=st.floats(0.05, 5.0), pos=st.lists(st.floats(-0.2, 0.2), min_size=3, max_size=3))
def test_point_mass_column_is_the_difference_of_a_compiled_payload(tool_columns, mass, pos):
    model, tau0, cols = tool_columns
    tau = inverse_dynamics(_with_point_mass(mass, pos), Q, QD, QDD)
    col = point_mass_columns(cols, pos)[:, :, 0]
    np.testing.assert_allclose(tau - tau0, mass * col, atol=1e-8 * (1 + np.abs(tau).max()))


def test_first_moment_columns_linearise_the_payload_position(tool_columns):
    """m Y(p) = m Y(c0) + m (p - c0) . dY/dp + O(m |p - c0|^2)."""
    model, tau0, cols = tool_columns
    c0 = np.array(model.body_ipos[TOOL])
    pc = point_mass_columns(cols, c0)
    for d in (0.02, 0.01):
        p = c0 + d * np.array([1.0, -0.5, 0.3])
        tau = inverse_dynamics(_with_point_mass(1.0, p), Q, QD, QDD)
        err = np.abs(tau - tau0 - pc[:, :, 0] - pc[:, :, 1:] @ (p - c0)).max()
        if d == 0.02:
            e2 = err
    assert err < e2 / 3, (err, e2)           # second order in the offset


def test_standard_parameters_round_trip_and_columns_are_exact(tool_columns):
    model, tau0, cols = tool_columns
    m2, _ = load_model(ARM_XML)
    theta = standard_params(m2, TOOL)
    delta = np.array([0.4, 0.01, -0.02, 0.005, 0.003, 0.002, 0.001, 0.0005, -0.0003, 0.0002])
    set_standard_params(m2, TOOL, theta + delta)
    np.testing.assert_allclose(standard_params(m2, TOOL), theta + delta, atol=1e-12)
    np.testing.assert_allclose(inverse_dynamics(m2, Q, QD, QDD), tau0 + cols @ delta, atol=1e-8)
    np.testing.assert_array_equal(standard_params(model, TOOL), theta)   # columns restore the model


def test_inverse_dynamics_matches_forward_simulation_of_the_truth():
    """mj_inverse of the recorded state and MuJoCo's forward acceleration agree (Euler steps)."""
    model = truth_model(ARM_XML, Hidden(damping={"elbow": 0.5}))
    data = mujoco.MjData(model)
    data.qpos[:] = [0.1, -0.4, 0.7]
    data.qvel[:] = [0.3, -0.2, 0.5]
    data.ctrl[:] = [0.5, 2.0, -1.0]
    mujoco.mj_forward(model, data)
    tau = inverse_dynamics(model, data.qpos[None], data.qvel[None], data.qacc[None])[0]
    np.testing.assert_allclose(tau, data.qfrc_actuator, atol=1e-9)
