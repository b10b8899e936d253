"""The CDPR model of a moving rigid platform (``cdpr_gravity`` + ``platform_inertia``) against the
Newton-Euler wrench of a translating rigid body written out here: the cables supply
``[m (a + g_up); m c x (a + g_up)]`` about the platform origin (c its centre of mass, world axes),
so the moment of the inertial force ``m c x a`` belongs to the model as much as ``m a`` does, and
with the centre of mass off the origin the fit must not move it into anything else."""
import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from cablelab.fit import identify
from cablelab.model import Model
from cablelab.plants.cdpr.dataset import CdprArrays, dataset_from_arrays
from cablelab.plants.cdpr.sim import default_description

G = 9.81


def _dataset(desc, p, a, R=None):
    n = len(p)
    arr = CdprArrays(t=np.arange(n) * 0.01, tensions=np.full((n, 8), 1000.0), motor_velocity=np.ones((n, 8)),
                     motor_effort=np.full((n, 8), np.nan), position=p, R=R, acc=a, velocity=np.zeros((n, 3)),
                     truth_mass=None, truth_com=None, source="dynamometer", scale=1.0)
    return dataset_from_arrays(arr, desc)


def _rotations(rng, n, angle):
    """(n, 3, 3) rotations about random axes by up to ``angle`` rad (Rodrigues)."""
    k = rng.normal(size=(n, 3))
    k /= np.linalg.norm(k, axis=1, keepdims=True)
    th = rng.uniform(-angle, angle, n)[:, None, None]
    K = np.zeros((n, 3, 3))
    K[:, 0, 1], K[:, 0, 2], K[:, 1, 2] = -k[:, 2], k[:, 1], -k[:, 0]
    K = K - np.transpose(K, (0, 2, 1))
    return np.eye(3) + np.sin(th) * K + (1 - np.cos(th)) * K @ K


def _newton_euler(m, c_world, a):
    f = a + np.array([0.0, 0.0, G])
    return np.concatenate([m * f, m * np.cross(c_world, f)], axis=1)


@settings(max_examples=20, deadline=None)
@given(m=st.floats(200.0, 1500.0), x=st.floats(-0.3, 0.3), y=st.floats(-0.3, 0.3), z=st.floats(-0.8, 0.3),
       seed=st.integers(0, 2**31 - 1))
def test_model_output_is_the_rigid_body_wrench_of_a_level_platform(m, x, y, z, seed):
    """Level platform, any centre of mass (its height only moves the moment of m a)."""
    rng = np.random.default_rng(seed)
    n = 50
    p = np.column_stack([rng.uniform(-1, 1, n), rng.uniform(-0.5, 0.5, n), rng.uniform(0.6, 1.2, n)])
    a = rng.normal(scale=0.5, size=(n, 3))
    ds = _dataset(default_description(), p, a)
    phi, cols, _ = Model("cdpr", ("cdpr_gravity", "platform_inertia")).regressor(ds)
    theta = {"m": m, "mx": m * x, "my": m * y, "m_a": m, "mx_a": m * x, "my_a": m * y, "mz_a": m * z}
    out = phi @ np.array([theta[c.name] for c in cols])
    np.testing.assert_allclose(out, _newton_euler(m, np.array([x, y, z]), a), rtol=1e-12, atol=1e-9)


def test_model_output_is_the_rigid_body_wrench_of_a_tilted_platform():
    """A tilted platform (rotation R), centre of mass in the platform's plane: first moments in
    the platform frame, the moments in world axes."""
    rng = np.random.default_rng(3)
    n, m, c = 80, 700.0, np.array([0.11, -0.07, 0.0])
    R = _rotations(rng, n, 0.2)
    p = np.column_stack([rng.uniform(-1, 1, n), rng.uniform(-0.5, 0.5, n), rng.uniform(0.6, 1.2, n)])
    a = rng.normal(scale=0.5, size=(n, 3))
    ds = _dataset(default_description(), p, a, R)
    phi, cols, _ = Model("cdpr", ("cdpr_gravity", "platform_inertia")).regressor(ds)
    theta = {"m": m, "mx": m * c[0], "my": m * c[1], "m_a": m, "mx_a": m * c[0], "my_a": m * c[1], "mz_a": 0.0}
    out = phi @ np.array([theta[k.name] for k in cols])
    np.testing.assert_allclose(out, _newton_euler(m, np.einsum("nij,j->ni", R, c), a), rtol=1e-12, atol=1e-9)


def test_offsets_mass_and_centre_of_mass_come_back_from_an_accelerated_platform():
    """The wrench the dynamometers (offsets b) report for a rigid payload off the origin,
    accelerated: the fit with the offsets recovers every parameter exactly (without the moment
    of m a the centre of mass and the offsets took it up: several percent off)."""
    rng = np.random.default_rng(11)
    desc = default_description()
    n, m, c = 600, 812.0, np.array([0.09, -0.11, 0.0])
    t = np.arange(n) * 0.05
    p = np.column_stack([1.0 * np.sin(0.21 * t), 0.5 * np.sin(0.37 * t + 1), 0.9 + 0.3 * np.sin(0.53 * t)])
    a = -np.column_stack([0.21 ** 2 * 1.0 * np.sin(0.21 * t), 0.37 ** 2 * 0.5 * np.sin(0.37 * t + 1),
                          0.53 ** 2 * 0.3 * np.sin(0.53 * t)]) + rng.normal(scale=0.2, size=(n, 3))
    b = rng.uniform(-80, 80, 8)
    ds = _dataset(desc, p, a)
    W = ds.signals["W"] + desc.cdpr.pulley_radius * ds.signals["pulley_S"]
    y = _newton_euler(m, c, a) + np.einsum("nij,j->ni", W, b)
    ds = ds.replace(y=y)
    r = identify(Model("cdpr", ("cdpr_gravity", "platform_inertia", "tension_sensor_offset")), ds)
    assert r.params["m"] == pytest.approx(m, rel=1e-9) and r.params["m_a"] == pytest.approx(m, rel=1e-9)
    assert [r.params["mx"], r.params["my"]] == pytest.approx(list(m * c[:2]), rel=1e-8)
    assert [r.params["mx_a"], r.params["my_a"]] == pytest.approx(list(m * c[:2]), rel=1e-8)
    np.testing.assert_allclose([r.params[f"b[winch_{i}]"] for i in range(1, 9)], b, rtol=1e-7, atol=1e-7)
    # without the first moments of the accelerated mass, the same data biases the offsets
    phi, cols, _ = Model("cdpr", ("cdpr_gravity", "platform_inertia", "tension_sensor_offset")).regressor(ds)
    keep = [i for i, k in enumerate(cols) if k.name not in ("mx_a", "my_a", "mz_a")]
    A = phi[:, :, keep].reshape(-1, len(keep))
    sol = np.linalg.lstsq(A, y.reshape(-1), rcond=None)[0]
    names = [cols[i].name for i in keep]
    b0 = np.array([sol[names.index(f"b[winch_{i}]")] for i in range(1, 9)])
    assert np.linalg.norm(b0 - b) / np.linalg.norm(b) > 0.01
