"""Generalised least squares for channels that mix independent sensors (:mod:`cablelab.fit.noise`,
``solve_linear`` with per-sample whitening).

Oracles: the closed-form GLS estimator ``(X^T V^-1 X)^-1 X^T V^-1 y`` with the block-diagonal
covariance ``V = diag(M_n diag(v) M_n^T)`` built densely (a second implementation); the known
variances the noise was drawn with; the estimator's stated covariance against its spread over
independent noise draws (Monte Carlo); Aitken's theorem (GLS has the smallest covariance of the
linear unbiased estimators, so it beats a per-channel weighting)."""
import numpy as np
import pytest
import scipy.linalg
import scipy.signal

from cablelab.effects.base import Param
from cablelab.fit.linear import solve_linear, weigh
from cablelab.fit.noise import noise_whitening, sensor_variances, whitening

SIG = np.array([0.2, 2.0, 0.5, 3.0, 1.0])        # sensor noise levels, up to 15x apart


def _problem(rng, n=1500, c=3, p=4, ar=0.0, sig=SIG):
    """Channels y_n = X_n theta + M_n e_n: M_n (c x s) a slowly turning map of the s sensors (like
    a cable robot's wrench matrix along a trajectory), e_n independent per sensor (AR(1) in time
    with coefficient ``ar``, marginal standard deviations ``sig``)."""
    s = sig.size
    t = np.linspace(0.0, 1.0, n)
    base = rng.normal(size=(c, s))
    turn = rng.normal(size=(c, s))
    m = base[None] + np.sin(2 * np.pi * t)[:, None, None] * turn[None]
    x = rng.normal(size=(n, c, p)) + np.cos(3 * np.pi * t)[:, None, None]
    theta = rng.normal(size=p)
    e = scipy.signal.lfilter([1.0], [1.0, -ar], rng.normal(size=(n, s)) * np.sqrt(1 - ar ** 2), axis=0) * sig
    y = x @ theta + np.einsum("ncs,ns->nc", m, e)
    return x, y, m, theta


def _params(p):
    return [Param(f"p{i}", "", 0.0, -np.inf, np.inf, "") for i in range(p)]


def test_whitened_solve_is_the_closed_form_gls():
    rng = np.random.default_rng(3)
    x, y, m, _ = _problem(rng, n=200)
    v = SIG ** 2
    fit = solve_linear(x, y, _params(x.shape[2]), channel_scale=whitening(m, v))
    # dense oracle: block-diagonal V, theta = (X^T V^-1 X)^-1 X^T V^-1 y
    blocks = [mi @ np.diag(v) @ mi.T for mi in m]
    vinv = np.linalg.inv(scipy.linalg.block_diag(*blocks))
    xx = x.reshape(-1, x.shape[2])
    info = xx.T @ vinv @ xx
    theta = np.linalg.solve(info, xx.T @ vinv @ y.reshape(-1))
    np.testing.assert_allclose(fit.theta, theta, rtol=1e-9, atol=1e-12)
    # its covariance is the GLS one up to the residual variance of the (normalised) weights
    r = y.reshape(-1) - xx @ theta
    scale = float(r @ vinv @ r) / (xx.shape[0] - xx.shape[1])
    np.testing.assert_allclose(fit.cov, scale * np.linalg.inv(info), rtol=1e-8)


def test_weigh_applies_each_samples_matrix():
    rng = np.random.default_rng(0)
    w = rng.normal(size=(5, 3, 3))
    x = rng.normal(size=(5, 3, 2))
    np.testing.assert_allclose(weigh(w, x), np.stack([w[i] @ x[i] for i in range(5)]))
    np.testing.assert_allclose(weigh(w, x[..., 0]), np.stack([w[i] @ x[i, :, 0] for i in range(5)]))
    np.testing.assert_allclose(weigh(np.array([1.0, 2.0, 3.0]), x), x * [[[1.0], [2.0], [3.0]]])


@pytest.mark.parametrize("ar", [0.0, 0.8])
def test_sensor_variances_recover_the_drawn_noise(ar):
    """The ML variances from the channels' residual match the drawn ones, for white and AR(1)
    noise alike (the marginal variance is what the whitening needs; coloured noise only makes
    the estimate of it less precise), the quiet sensors included."""
    rng = np.random.default_rng(11)
    x, y, m, theta = _problem(rng, n=4000, ar=ar)     # (the rows the estimate uses at most)
    fit = solve_linear(x, y, _params(x.shape[2]), channel_scale="rms")
    resid = y - x @ fit.theta
    v = sensor_variances(resid, m)
    # Cramer-Rao bound of the variances of independent Gaussian samples r_n ~ N(0, C_n):
    # I_kl = 1/2 sum_n (m_k^T C_n^-1 m_l)^2, written out here sample by sample
    info = np.zeros((SIG.size, SIG.size))
    for mn in m[::10]:
        g = mn.T @ np.linalg.inv(mn @ np.diag(SIG ** 2) @ mn.T) @ mn
        info += 0.5 * g ** 2
    sd = np.sqrt(np.diag(np.linalg.inv(info * 10)))
    # white noise: within 4 bounds; AR(1) at 0.8 has about (1 + a^2) / (1 - a^2) = 4.6 times
    # fewer independent samples for a second moment
    k = 4.0 if ar == 0 else 4.0 * np.sqrt((1 + ar ** 2) / (1 - ar ** 2))
    assert np.all(np.abs(v - SIG ** 2) < k * sd), (np.sqrt(v), SIG)


def test_feasible_gls_has_its_stated_covariance_and_beats_channel_weights():
    """Over independent noise draws: the feasible-GLS estimate's spread matches its stated
    covariance (mean squared Mahalanobis error ~ p), and its error covariance is smaller than that
    of the per-channel noise weighting (Aitken)."""
    rng = np.random.default_rng(5)
    x, _, m, theta = _problem(rng, n=1200)
    p = x.shape[2]
    z2, err_gls, err_diag = [], [], []
    for k in range(120):
        r = np.random.default_rng(1000 + k)
        e = r.normal(size=(x.shape[0], SIG.size)) * SIG
        y = x @ theta + np.einsum("ncs,ns->nc", m, e)
        first = solve_linear(x, y, _params(p), channel_scale="rms")
        resid = y - x @ first.theta
        gls = solve_linear(x, y, _params(p), channel_scale=noise_whitening(resid, m))
        sd = resid.std(axis=0)
        diag = solve_linear(x, y, _params(p), channel_scale=1.0 / sd)
        d = gls.theta - theta
        z2.append(float(d @ np.linalg.solve(gls.cov, d)))
        err_gls.append(d)
        err_diag.append(diag.theta - theta)
    assert np.mean(z2) == pytest.approx(p, rel=0.25)
    mse_gls = np.mean(np.sum(np.square(err_gls), axis=1))
    mse_diag = np.mean(np.sum(np.square(err_diag), axis=1))
    assert mse_gls < 0.7 * mse_diag


def test_a_sample_without_noise_on_a_channel_keeps_a_finite_weight():
    """A channel no sensor reaches at some samples (a zero row of the map, e.g. a masked channel)
    still gives finite whitening matrices and a fit equal to leaving those rows' channel out."""
    rng = np.random.default_rng(2)
    x, y, m, _ = _problem(rng, n=300)
    m = m.copy()
    m[:50, 0, :] = 0.0
    x = x.copy()
    y = y.copy()
    x[:50, 0, :] = 0.0
    y[:50, 0] = 0.0
    w = whitening(m, SIG ** 2)
    assert np.all(np.isfinite(w))
    fit = solve_linear(x, y, _params(x.shape[2]), channel_scale=w)
    # oracle: the same GLS without the empty channel on those samples (dense, as above)
    rows_x, rows_y, blocks = [], [], []
    for i in range(x.shape[0]):
        keep = slice(1, None) if i < 50 else slice(None)
        rows_x.append(x[i, keep])
        rows_y.append(y[i, keep])
        blocks.append(m[i, keep] @ np.diag(SIG ** 2) @ m[i, keep].T)
    vinv = np.linalg.inv(scipy.linalg.block_diag(*blocks))
    xx, yy = np.concatenate(rows_x), np.concatenate(rows_y)
    theta = np.linalg.solve(xx.T @ vinv @ xx, xx.T @ vinv @ yy)
    np.testing.assert_allclose(fit.theta, theta, rtol=1e-7)
