"""The CDPR fit weighs the cables, not the wrench channels: the wrench channels ``W(p) d`` mix eight
dynamometers whose noise levels differ (up to ten times), and the fit whitens each sample with
``W diag(v) W^T`` (``Dataset.noise_map``, :mod:`cablelab.fit.noise`).

Oracles: the benchmark generator's own statics (bench/cases_cdpr.py: minimum-norm tensions about a
pretension, the platform's off-centre weight and inertial force), the offsets and noise levels it
was given, and the spread of the fitted offsets over independent noise draws (their stated
covariance must describe it; Aitken: the whitened fit must beat one weight per channel)."""
import os
import sys

import numpy as np
import pytest
import scipy.signal

from cablelab.description import parse_description, read_yaml
from cablelab.fit import identify
from cablelab.model import Model
from cablelab.plants.cdpr.dataset import CdprArrays, dataset_from_arrays

sys.path.insert(0, os.path.join(os.path.dirname(__file__), "..", "..", "..", "bench"))
import cases_cdpr  # noqa: E402

M = 600.0
FS = 25.0
NOISE_REL = np.array([0.004, 0.03, 0.004, 0.02, 0.03, 0.005, 0.004, 0.03])   # of the mean tension


def _truth(duration=120.0):
    """Slow motion through the workspace (three incommensurate periods), level platform, payload
    off the origin: exact tensions from the generator."""
    t = np.arange(0.0, duration, 1.0 / FS)
    w = 2 * np.pi / np.array([40.0, 27.0, 33.0])
    amp = np.array([0.9, 0.3, 0.2])
    p = np.array([0.0, 0.0, 0.85]) + amp * np.sin(w * t[:, None])
    v = amp * w * np.cos(w * t[:, None])
    a = -amp * w ** 2 * np.sin(w * t[:, None])
    tr = {"m": M, "r_p": 0.0, "com": np.array([0.08, -0.05, 0.0]), "Fc": np.zeros(8), "Fv": np.zeros(8),
          "eps": 1.0}
    ten = cases_cdpr._winch_truth(tr, p, v, a, t)[2]
    return t, p, v, a, ten


def _dataset(desc, t, p, v, a, readings):
    n = len(t)
    arr = CdprArrays(t=t, tensions=readings, motor_velocity=np.ones((n, 8)), motor_effort=np.full((n, 8), np.nan),
                     position=p, R=None, acc=a, velocity=v, truth_mass=None, truth_com=None,
                     source="dynamometer", scale=1.0)
    return dataset_from_arrays(arr, desc)


@pytest.fixture(scope="module", params=[0.0, 0.7], ids=["white", "ar0.7"])
def draws(request):
    """Fitted offsets (whitened and per-channel weighted) and the stated covariance over
    independent noise draws, with hidden offsets and without (a control); white or AR(1) cable
    noise (the dynamometers' coloured noise of the benchmark cases)."""
    ar = request.param
    desc = parse_description(read_yaml(cases_cdpr._description(M, 0.0)))
    t, p, v, a, ten = _truth()
    sig = NOISE_REL * cases_cdpr.mean_tension(M)
    rng = np.random.default_rng(4)
    b = rng.choice([-1, 1], 8) * rng.uniform(0.03, 0.1, 8) * cases_cdpr.mean_tension(M)
    model = Model("cdpr", ("cdpr_gravity", "platform_inertia", "tension_sensor_offset"))
    out = {"b": b, "gls": [], "diag": [], "z2": [], "z2_control": []}
    names = [f"b[winch_{i}]" for i in range(1, 9)]
    for k in range(16):
        r = np.random.default_rng(100 + k)
        noise = scipy.signal.lfilter([1.0], [1.0, -ar], r.normal(size=ten.shape), axis=0) * np.sqrt(1 - ar ** 2) * sig
        for offsets, key in ((b, "z2"), (np.zeros(8), "z2_control")):
            ds = _dataset(desc, t, p, v, a, ten + offsets + noise)
            fit = identify(model, ds)
            bf = np.array([fit.params[nm] for nm in names])
            cn, cov = fit.extra["cov"]
            idx = [cn.index(nm) for nm in names]
            d = bf - offsets
            out[key].append(float(d @ np.linalg.solve(cov[np.ix_(idx, idx)], d)))
            if key == "z2":
                out["gls"].append(d)
                diag = identify(model, ds.replace(noise_map=None))
                out["diag"].append(np.array([diag.params[nm] for nm in names]) - offsets)
    return out


def test_whitened_offsets_beat_channel_weights(draws):
    mse_gls = np.mean(np.sum(np.square(draws["gls"]), axis=1))
    mse_diag = np.mean(np.sum(np.square(draws["diag"]), axis=1))
    assert mse_gls < 0.5 * mse_diag


def test_stated_covariance_describes_the_spread(draws):
    """Mean of the squared Mahalanobis error of the eight offsets ~ 8 (chi^2_8) over the draws:
    the covariance neither hides the error nor overstates it, with white noise and with AR(1)
    noise (whose slow-band variance, (1 + a) / (1 - a) times the white one, the standard errors
    carry through the residual's AR(1) inflation); the control without offsets likewise, so its
    offsets stay within their noise."""
    for key in ("z2", "z2_control"):
        z2 = np.array(draws[key])
        assert 8 * 0.5 < z2.mean() < 8 * 1.5, (key, z2)
