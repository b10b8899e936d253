"""The design's batched cost (k motions stacked on one time axis, one regressor, batched
information matrices: :func:`cablelab.excite.block_conditions`) equals the single-motion condition
number (:func:`cablelab.excite.condition`, QR and Schur complement) of each motion on its own, and
the linear Fourier basis reproduces the series written out term by term."""
from pathlib import Path

import numpy as np
import pytest

import cablelab.plants.crane as crane_pkg
from cablelab import excite as E
from cablelab.description import load_description
from cablelab.registry import get_plant


def test_stacked_conditions_equal_one_by_one():
    desc = load_description(str(Path(crane_pkg.__file__).parent / "data" / "crane.yaml"))
    ex = E.get_exciter("crane")
    lim, h = ex.limits(desc), ex.harmonics
    shape = (len(lim.joints), 2, h)
    t = np.arange(0.0, 30.0, 1.0 / (10 * ex.base_hz * h))
    basis = E.fourier_basis(t, ex.base_hz, h, 30.0)
    xs = np.random.default_rng(1).normal(size=(5, int(np.prod(shape))))
    xs[4] = 0.0                                   # no motion at all: nothing excited
    for params in (["OF[hoist]", "m"], ["OF[luff]", "m_c"]):
        probe = ex.motion_dataset(t, *E.scaled_motion(np.ones(shape), t, lim, ex.base_hz, 30.0), desc)
        model, _ = E.model_for(get_plant("crane"), desc, params, probe)
        ds = ex.motion_dataset(*E._stacked_motion(xs, basis, t, lim, shape), desc)
        batched = E.block_conditions(model, ds, len(xs), params)
        one = [E.condition(model, ex.motion_dataset(
            t, *E.scaled_motion(x.reshape(shape), t, lim, ex.base_hz, 30.0), desc), params) for x in xs]
        assert np.isinf(one[4]) and np.isinf(batched[4])
        assert batched[:4] == pytest.approx(one[:4], rel=1e-6)


def test_fourier_basis_is_the_series():
    t = np.linspace(0.0, 20.0, 8001)
    coef = np.random.default_rng(2).normal(size=(2, 2, 3))
    x, xd, xdd = E.fourier_motion(coef, t, 0.1, 20.0)
    w, wd, wdd = E._window(t, 20.0)
    for j in range(2):
        raw = sum(coef[j, 0, k] / (2 * np.pi * 0.1 * (k + 1)) * np.sin(2 * np.pi * 0.1 * (k + 1) * t)
                  - coef[j, 1, k] / (2 * np.pi * 0.1 * (k + 1)) * np.cos(2 * np.pi * 0.1 * (k + 1) * t)
                  for k in range(3))
        raw = raw - raw[0]
        assert x[:, j] == pytest.approx(w * raw, abs=1e-12)
        # derivatives: against the numerical derivative of the position
        assert xd[5:-5, j] == pytest.approx(np.gradient(x[:, j], t)[5:-5], abs=2e-3)
        # (away from the window's corners at 2 s and 18 s, where the jerk jumps and the
        # central difference of xd is off by O(dt))
        smooth = (np.abs(t - 2.0) > 0.01) & (np.abs(t - 18.0) > 0.01)
        smooth[:5] = smooth[-5:] = False
        assert xdd[smooth, j] == pytest.approx(np.gradient(xd[:, j], t)[smooth], abs=2e-3)


def test_pose_reference_round_trip(tmp_path):
    """A CDPR design is written as the platform's pose (MultiDOFJointTrajectory, level) and read
    back as the same x, y, z with their velocities and accelerations."""
    from cablelab.bags import open_bag
    from cablelab.plants.cdpr.sim import default_description
    from cablelab.plants.cdpr.topics import REFERENCE

    desc = default_description()
    d = E.design("cdpr", desc, ["b[winch_1]", "m"], duration=16.0, max_iter=2)
    E.write_reference(tmp_path / "ref", d, E.get_exciter("cdpr"))
    tr = open_bag(tmp_path / "ref").multidof_trajectory(REFERENCE)
    assert tr.quaternion[:, 3] == pytest.approx(1.0) and np.allclose(tr.quaternion[:, :3], 0.0)
    q, qd, qdd = E.read_reference(tmp_path / "ref", REFERENCE, ("x", "y", "z"))(d.t - d.t[0])
    assert q == pytest.approx(d.q, abs=1e-9) and qd == pytest.approx(d.qd, abs=1e-9)
    assert qdd == pytest.approx(d.qdd, abs=1e-9)
