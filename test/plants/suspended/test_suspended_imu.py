"""IMU input of the swing estimator (spec 000_suspended.md sec. 5.2): yaw and yaw rate from a
platform IMU (orientation + gyro, as MuJoCo's gyro sensor reads it) instead of the pose's finite
difference. Oracles: the yaw derivative from the simulated pose at 1 ms (the integrator's own
kinematics), and central differences on random rotations for the closed-form yaw-rate formula."""
import mujoco
import numpy as np
import pytest

from cablelab.plants.suspended.mjcf import build_virtual
from cablelab.plants.suspended.params import parameter_set
from cablelab.plants.suspended.sim import STATE_SPEC, initial_state, platform_imu
from cablelab.plants.suspended.swing import SwingEstimator, yaw_from_quat, yaw_rate
from cablelab.rotations import quat_to_matrix


def test_yaw_rate_formula_is_the_derivative_of_atan2_R10_R00():
    rng = np.random.default_rng(4)
    q0 = rng.normal(size=(50, 4))
    w = rng.normal(size=(50, 3))                     # world angular velocity, rad/s
    h = 1e-6
    R = quat_to_matrix(q0)
    # R(t) = exp([w]x t) R0: first order is enough for a central difference at h = 1e-6
    def rot(sign):
        from scipy.spatial.transform import Rotation
        return Rotation.from_rotvec(sign * h * w).as_matrix() @ R
    fd = (np.arctan2(rot(1)[:, 1, 0], rot(1)[:, 0, 0]) - np.arctan2(rot(-1)[:, 1, 0], rot(-1)[:, 0, 0])) / (2 * h)
    assert np.allclose(yaw_rate(R, w), fd, atol=1e-6)


def _run(T=3.0):
    # the virtual-joint model (smooth: the 4-tendon truth plant's soft cable limits ring at high
    # frequency, which a 1 ms central difference would not resolve), swinging and yawing
    p = parameter_set("licas")
    m = build_virtual(p)
    d = mujoco.MjData(m)
    q0 = {"J7": 0.3, "J8": 0.1, "J11": -0.1, "J9": -0.05, "J12": 0.05}   # levelled start
    mujoco.mj_setState(m, d, initial_state(m, q0), STATE_SPEC)
    site = m.site("platform").id
    n = int(T / m.opt.timestep)
    t, pos, quat, gyro = np.empty(n), np.empty((n, 3)), np.empty((n, 4)), np.empty((n, 3))
    for i in range(n):
        mujoco.mj_step(m, d)
        mujoco.mj_forward(m, d)
        t[i], pos[i], quat[i] = d.time, d.sensordata[:3], d.sensordata[3:7]
        gyro[i] = platform_imu(m, d, site)[0]
    return p, t, pos, quat, gyro


def test_imu_yaw_rate_is_exact_and_beats_the_filtered_pose_difference():
    p, t, pos, quat, gyro = _run()
    yaw = np.unwrap(yaw_from_quat(quat))
    # oracle: MuJoCo's semi-implicit Euler moves the pose with the new velocity (q_k = q_(k-1) +
    # dt v_k), so the backward difference of the pose yaw is the yaw rate at step k
    exact = (yaw[1:-1] - yaw[:-2]) / (t[1:-1] - t[:-2])
    rest = np.array(p.S) - [0, 0, p.L]
    with_imu = SwingEstimator(p.S, rest_pos=rest, rest_yaw=0.0)
    pose_only = SwingEstimator(p.S, rest_pos=rest, rest_yaw=0.0)
    v_imu, v_pose, src = [], [], []
    for k in range(1, len(t) - 1, 10):              # poses and IMU at 100 Hz
        assert with_imu.imu(t[k], quat[k], gyro[k])
        s = with_imu.step(t[k], pos[k], quat[k])
        v_imu.append(s.velocity[2])
        src.append(s.source)
        v_pose.append(pose_only.step(t[k], pos[k], quat[k]).velocity[2])
    ref = exact[0:len(t) - 2:10]
    assert set(src) == {"imu"}
    assert np.abs(np.array(v_imu) - ref).max() < 1e-4 * np.abs(ref).max()
    late = slice(20, None)                           # after the pose filter's start-up
    err_pose = np.sqrt(np.mean((np.array(v_pose)[late] - ref[late]) ** 2))
    err_imu = np.sqrt(np.mean((np.array(v_imu)[late] - ref[late]) ** 2))
    assert err_imu < 0.01 * err_pose                 # no low-pass lag (tau = 0.05 s at 3.6 rad/s)
    assert np.abs(ref).max() > 0.5                   # it really turned


def test_nan_or_old_imu_falls_back_to_the_pose():
    p, t, pos, quat, gyro = _run(0.5)
    est = SwingEstimator(p.S, rest_pos=np.array(p.S) - [0, 0, p.L], rest_yaw=0.0, imu_max_lag=0.05)
    assert est.imu(t[0], quat[0], gyro[0])
    assert not est.imu(t[10], [np.nan, 0, 0, 1], gyro[10])       # NaN: ignored
    assert not est.imu(t[10], quat[10], gyro[10][:2])             # wrong length: ignored
    assert est.step(t[20], pos[20], quat[20]).source == "imu"     # 20 ms after the good sample
    s = est.step(t[200], pos[200], quat[200])                     # 200 ms later: too old
    assert s.source == "pose" and s.position[2] == pytest.approx(yaw_from_quat(quat[200]), abs=1e-12)
