"""The ROS-free simulator's published state (what ``cable_sim_node --plant mjcf`` sends each
period) against MuJoCo's own quantities: the measured tendons' tensions through the tendon
Jacobian give MuJoCo's generalised actuator force (every actuator of the camera robot pulls a
measured cable, so no joint effort is measured besides), and advancing in one call or step by step lands on the same state."""
import mujoco
import numpy as np

from cablelab.description import load_description
from cablelab.plants.mjcf.examples import CABLECAM, text
from cablelab.plants.mjcf.sim import MjcfSim, description_yaml

CABLES = ["cable_1", "cable_2", "cable_3", "cable_4"]


def _sim():
    desc = load_description(description_yaml(text(CABLECAM), tendons=CABLES))
    return MjcfSim(desc.mjcf, desc.gravity)


def test_tensions_through_the_tendon_jacobian_are_the_actuator_force():
    sim = _sim()
    rng = np.random.default_rng(1)
    for _ in range(5):
        sim.advance(-np.abs(rng.normal(40.0, 10.0, sim.model.nu)), 0.01)
        t, q, qd, effort, tension = sim.state()
        assert tension.shape == (4,) and np.all(tension > 0)       # cables pull
        ten_j = sim.data.ten_J.reshape(sim.model.ntendon, sim.model.nv)
        qfrc = sim.data.qfrc_actuator
        np.testing.assert_allclose(qfrc, -ten_j.T @ tension, atol=1e-9 * (1 + np.abs(qfrc).max()))
        np.testing.assert_array_equal(effort, np.zeros(sim.model.nv))   # no joint actuator
        np.testing.assert_array_equal(q, sim.data.qpos[: sim.model.nv])
        assert t == sim.data.time


def test_one_advance_of_many_steps_equals_the_steps_one_by_one():
    a, b = _sim(), _sim()
    ctrl = np.full(a.model.nu, -35.0)
    a.advance(ctrl, 20 * a.model.opt.timestep)
    for _ in range(20):
        b.advance(ctrl, b.model.opt.timestep)
    for x, y in zip(a.state(), b.state()):
        np.testing.assert_array_equal(x, y)
    ref = mujoco.MjData(a.model)
    mujoco.mj_forward(a.model, ref)
    ref.ctrl[:] = ctrl
    mujoco.mj_step(a.model, ref, nstep=20)
    np.testing.assert_array_equal(a.state()[1], ref.qpos[: a.model.nv])


def test_joint_effort_is_the_joint_actuators_generalised_force():
    """The precomputed joint-actuator moments (gear at a hinge/slide dof) against MuJoCo's own
    actuator moment matrix of the current state, on the arm (joint motors) and the gantry."""
    from cablelab.plants.mjcf.examples import ARM3, GANTRY
    from cablelab.plants.mjcf.sim import actuator_moments

    for example in (ARM3, GANTRY):
        sim = MjcfSim(load_description(description_yaml(text(example))).mjcf, 9.81)
        rng = np.random.default_rng(2)
        for _ in range(3):
            sim.advance(rng.normal(0.0, 5.0, sim.model.nu), 0.01)
            effort = sim.state()[3]
            on = sim.model.actuator_trntype == mujoco.mjtTrn.mjTRN_JOINT
            want = actuator_moments(sim.model, sim.data)[on].T @ sim.data.actuator_force[on]
            np.testing.assert_allclose(effort, want, rtol=1e-12, atol=1e-12)
            assert np.any(effort != 0)
