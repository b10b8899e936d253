"""Recursive least squares with exponential forgetting, batch-vectorised.

For ``y = Phi theta + e``: minimises ``sum_k lambda^(N-k) (y_k - phi_k theta)^2`` plus the prior
``(theta - theta0)^T P0^-1 (theta - theta0)``. A batch update of n rows is the exact
information-form update (``P^-1 <- lambda^n P^-1 + Phi^T W Phi``) with per-row weights
``lambda^(n-1-k)``, so feeding rows one at a time or in one batch gives the same estimate (tested).
"""
from __future__ import annotations

import numpy as np


class RecursiveLeastSquares:
    """Args: p parameters, forgetting factor lam in (0, 1], prior theta0 and covariance scale."""

    def __init__(self, p: int, lam: float = 1.0, theta0=None, p0: float = 1e6):
        if not 0 < lam <= 1:
            raise ValueError(f"forgetting factor must be in (0, 1], got {lam}")
        self.lam = lam
        self.theta = np.zeros(p) if theta0 is None else np.asarray(theta0, dtype=float).copy()
        self.info = np.eye(p) / p0  # P^-1
        self.rhs = self.info @ self.theta
        self.n = 0

    def update(self, phi, y) -> np.ndarray:
        """Add rows phi (n, p) with outputs y (n,); rows with non-finite values are skipped."""
        phi = np.atleast_2d(np.asarray(phi, dtype=float))
        y = np.asarray(y, dtype=float).reshape(-1)
        ok = np.isfinite(phi).all(axis=1) & np.isfinite(y)
        n = len(y)
        w = self.lam ** np.arange(n - 1, -1, -1.0) * ok
        phi = np.where(ok[:, None], phi, 0.0)
        y = np.where(ok, y, 0.0)
        decay = self.lam ** n
        self.info = decay * self.info + (phi * w[:, None]).T @ phi
        self.rhs = decay * self.rhs + (phi * w[:, None]).T @ y
        self.theta = np.linalg.solve(self.info, self.rhs)
        self.n += int(ok.sum())
        return self.theta

    @property
    def covariance(self) -> np.ndarray:
        """P = (information)^-1 (scaled by the noise variance gives the parameter covariance)."""
        return np.linalg.inv(self.info)
