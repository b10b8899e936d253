"""The Gram-matrix path of :func:`cablelab.fit.linear.solve_linear` against its second
implementation in the same module, the SVD of the tall column-scaled regressor (forced by
setting ``GRAM_COND`` to 0): random, badly scaled, ill-conditioned, bounded and rank-deficient
regressors give the same fit to round-off, and regressors beyond the Gram path's condition limit
go to the SVD path."""
import numpy as np
import pytest
from hypothesis import given, settings, strategies as st

from cablelab.effects.base import Param
from cablelab.errors import CablelabError
from cablelab.fit import linear
from cablelab.fit.linear import solve_linear


def _both(*args, **kw):
    fast = solve_linear(*args, **kw)
    with pytest.MonkeyPatch.context() as m:
        m.setattr(linear, "GRAM_COND", 0.0)        # every fit through the SVD
        direct = solve_linear(*args, **kw)
    return fast, direct


def _assert_same(fast, direct, rtol):
    assert fast.rank == direct.rank and fast.n == direct.n and fast.names == direct.names
    scale = np.sqrt(np.diag(direct.cov))          # compare on the estimates' own scale
    assert np.all(np.abs(fast.theta - direct.theta) <= rtol * (np.abs(direct.theta) + scale))
    np.testing.assert_allclose(fast.stderr, direct.stderr, rtol=rtol)
    np.testing.assert_allclose(fast.cov, direct.cov, rtol=rtol, atol=rtol * np.outer(scale, scale).max())
    assert fast.rss == pytest.approx(direct.rss, rel=rtol)
    assert fast.cond == pytest.approx(direct.cond, rel=max(rtol, 1e-6))
    assert fast.active_bounds == direct.active_bounds
    np.testing.assert_array_equal(fast.channel_scale, direct.channel_scale)


def _problem(rng, n, c, p, log_scale, mix):
    """(n, c, p) regressor with column scales 10^[-log_scale, log_scale] and columns mixed
    towards each other by ``mix`` (1: independent, -> 0: nearly collinear)."""
    base = rng.normal(size=(n, c, p))
    common = rng.normal(size=(n, c, 1))
    phi = mix * base + (1.0 - mix) * common
    phi = phi * 10.0 ** rng.uniform(-log_scale, log_scale, size=p)
    theta = rng.normal(size=p) / np.sqrt(np.mean(phi ** 2, axis=(0, 1)))
    y = phi @ theta + 0.1 * rng.normal(size=(n, c)) * np.arange(1, c + 1)
    return phi, y


@settings(max_examples=40, deadline=None)
@given(seed=st.integers(0, 2 ** 31), n=st.integers(40, 400), c=st.integers(1, 4),
       p=st.integers(1, 8), log_scale=st.floats(0.0, 4.0), mix=st.floats(0.02, 1.0))
def test_gram_path_matches_svd_path(seed, n, c, p, log_scale, mix):
    rng = np.random.default_rng(seed)
    phi, y = _problem(rng, n, c, p, log_scale, mix)
    valid = rng.uniform(size=n) > 0.1
    params = [Param(f"p{i}", "-") for i in range(p)]
    fast, direct = _both(phi, y, params, valid=valid)
    _assert_same(fast, direct, 1e-8)


@pytest.mark.parametrize("eps", [1e-2, 1e-3, 3e-6])
def test_ill_conditioned_regressor_same_fit_within_its_conditioning(eps):
    rng = np.random.default_rng(3)
    n = 3000
    x = rng.normal(size=n)
    phi = np.stack([x, x + eps * rng.normal(size=n), rng.normal(size=n)], axis=1)
    y = phi @ np.array([1.0, -2.0, 0.5]) + 0.01 * rng.normal(size=n)
    params = [Param(k, "-") for k in "abc"]
    fast, direct = _both(phi, y, params)
    # backward-stable solvers agree to about eps_machine x cond^2 on the estimates
    _assert_same(fast, direct, max(1e-9, 1e-15 * direct.cond ** 2))
    assert (direct.cond < linear.GRAM_COND) == (eps > 1e-4)


def test_beyond_the_condition_limit_the_svd_path_decides():
    rng = np.random.default_rng(4)
    x = rng.normal(size=500)
    phi = np.stack([x, x + 1e-7 * rng.normal(size=500), rng.normal(size=500)], axis=1)
    y = phi @ np.array([1.0, 1.0, 1.0])
    params = [Param(k, "-") for k in "abc"]
    fast, direct = _both(phi, y, params)
    assert fast.cond > linear.GRAM_COND
    np.testing.assert_array_equal(fast.theta, direct.theta)      # the same computation
    # exactly dependent columns: the same one-line refusal naming the direction
    phi[:, 1] = 2.0 * x
    with pytest.raises(CablelabError, match=r"rank 2 of 3.*a.*b"):
        solve_linear(phi, y, params)
    # a column at round-off level next to the others: not excited, as before
    phi[:, 1] = 1e-12 * x
    with pytest.raises(CablelabError, match=r"rank 2 of 3"):
        solve_linear(phi, y, params)


@settings(max_examples=25, deadline=None)
@given(seed=st.integers(0, 2 ** 31), p=st.integers(2, 6), c=st.integers(1, 3))
def test_bounded_fit_same_active_set_and_estimates(seed, p, c):
    rng = np.random.default_rng(seed)
    phi, y = _problem(rng, 300, c, p, 2.0, 0.5)
    free = solve_linear(phi, y, [Param(f"p{i}", "-") for i in range(p)])
    # bounds cutting through the unconstrained solution: some parameters end on a bound
    lo = np.where(rng.uniform(size=p) < 0.5, free.theta + np.abs(free.theta) * 0.3, -np.inf)
    hi = np.where(np.isfinite(lo), np.inf, free.theta - np.abs(free.theta) * 0.3)
    params = [Param(f"p{i}", "-", 0.0, lo[i], hi[i]) for i in range(p)]
    fast, direct = _both(phi, y, params)
    assert direct.active_bounds
    _assert_same(fast, direct, 1e-7)
    assert np.all(fast.theta >= lo - 1e-12) and np.all(fast.theta <= hi + 1e-12)
