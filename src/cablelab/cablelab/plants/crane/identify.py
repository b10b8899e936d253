"""Regressor identification of the crane's parameter groups (002 ch. 4, sec. 5.2-5.3, 6.2).

``tau_tot = Y_tot pi`` stacks the 5 equations of every sample (002 sec. 5.2: 3 actuated rows with
the measured efforts, 2 swing rows with 0) - built in one vectorised call, not sample by sample
behind a waitbar. The 9 groups of 002 eq. 4.2 are not all identifiable: the stacked regressor
has rank 6 (002 sec. 5.3.2), because

* l_b^2 m_b, l_b^2 m and l_c^2 m_c only appear as J = l_b^2 m_b / 4 + l_b^2 m + l_c^2 m_c
  (the boom-side inertia, coefficient of cos^2(beta) alpha_ddot and beta_ddot), and
* l_b m_b and l_c m_c only appear as l_b m_b / 2 - l_c m_c in the gravity term (002 eq. 6.9).

:func:`null_space` computes these directions from the data; :data:`FIX_002` are the three
measurable groups 002 fixed to close the rank (l_b^2 m from the measured m and l_b, and
l_c^2 m_c, l_c m_c from the measured counterbalance). Bounds keep the solution physical
(all groups >= 0); :func:`physical_check` says whether an unconstrained estimate is.
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from ...fit.linear import LinearFit, solve_linear
from ...effects.base import Param
from .model import GROUP_UNITS, PARAM_GROUPS, regressor

__all__ = ["FIX_002", "group_params", "stacked_regressor", "null_space", "identify_groups",
           "physical_check", "GroupFit"]

#: groups 002 fixed from measurements (sec. 5.3.2): l_b^2 m, l_c^2 m_c, l_c m_c
FIX_002 = ("lb2_m", "lc2_mc", "lc_mc")

_DOC = {
    "I_tot": "slew inertia of the crane about z", "lb2_mb": "l_b^2 m_b", "lb2_m": "l_b^2 m",
    "lb_m": "l_b m", "m": "payload mass", "lb_mb": "l_b m_b", "I_b": "luff inertia of the boom",
    "lc2_mc": "l_c^2 m_c", "lc_mc": "l_c m_c",
}


def group_params(names=PARAM_GROUPS) -> list[Param]:
    """:class:`Param` of the 002 eq. 4.2 groups (physical bounds: every group >= 0)."""
    units = dict(zip(PARAM_GROUPS, GROUP_UNITS))
    return [Param(n, units[n], 0.0, 0.0, np.inf, _DOC[n]) for n in names]


def stacked_regressor(q, qd, qdd, tau, g: float = 9.81) -> tuple[np.ndarray, np.ndarray]:
    """``(Y_tot (5N, 9), tau_tot (5N,))`` of 002 sec. 5.2 (swing rows with tau = 0).

    Args:
        q, qd, qdd: (N, 5) [alpha, beta, d, theta1, theta2] and derivatives.
        tau: (N, 3) measured [slew N m, luff N m, hoist N].
    """
    Y = regressor(q, qd, qdd, g)
    t = np.zeros((Y.shape[0], 5))
    t[:, :3] = tau
    return Y.reshape(-1, 9), t.reshape(-1)


def null_space(Y_tot: np.ndarray, rel_tol: float = 1e-8) -> tuple[int, np.ndarray]:
    """``(rank, N)`` of the column-scaled stacked regressor; N (9, 9 - rank) spans the groups'
    unidentifiable directions (in unscaled parameter units)."""
    s = np.linalg.norm(Y_tot, axis=0)
    s = np.where(s > 0, s, 1.0)
    _, sv, vt = np.linalg.svd(Y_tot / s, full_matrices=False)
    rank = int(np.sum(sv > sv[0] * rel_tol))
    n = vt[rank:].T / s[:, None]
    return rank, n / np.linalg.norm(n, axis=0)


@dataclass
class GroupFit:
    """Identified groups: ``values`` by name (fixed ones included), ``fit`` the free LS result."""

    values: dict
    fit: LinearFit
    fixed: dict

    @property
    def pi(self) -> np.ndarray:
        return np.array([self.values[n] for n in PARAM_GROUPS])


def identify_groups(q, qd, qdd, tau, *, g: float = 9.81, fixed: dict | None = None,
                    bounded: bool = True, extra_columns: np.ndarray | None = None,
                    extra_params: list[Param] | None = None, rows: int = 5) -> GroupFit:
    """Least squares for the free groups with the ``fixed`` ones moved to the left (002 sec. 5.3.2).

    Args:
        q, qd, qdd: (N, 5); tau: (N, 3) measured efforts.
        fixed: group name -> known value (e.g. from :meth:`CraneParams.groups` for FIX_002).
        bounded: enforce groups >= 0 (bounded LS) if the free solution leaves them.
        extra_columns: (N, 3, k) regressor columns of further effects on the actuated rows
            (friction, base tilt) and ``extra_params`` their :class:`Param`.
        rows: 5 = use the swing equations too (002), 3 = actuated rows only.
    """
    fixed = dict(fixed or {})
    Y = regressor(q, qd, qdd, g)[:, :rows, :]
    y = np.zeros((Y.shape[0], rows))
    y[:, :3] = tau
    idx_fixed = [PARAM_GROUPS.index(k) for k in fixed]
    idx_free = [i for i in range(9) if i not in idx_fixed]
    if idx_fixed:
        y = y - Y[:, :, idx_fixed] @ np.array([fixed[PARAM_GROUPS[i]] for i in idx_fixed])
    phi = Y[:, :, idx_free]
    params = group_params([PARAM_GROUPS[i] for i in idx_free])
    if extra_columns is not None:
        ex = np.zeros((Y.shape[0], rows, extra_columns.shape[2]))
        ex[:, :3] = extra_columns
        phi = np.concatenate([phi, ex], axis=2)
        params = params + list(extra_params)
    fit = solve_linear(phi, y, params, channel_scale=None, bounded=bounded)
    values = {**fixed, **fit.params}
    return GroupFit(values=values, fit=fit, fixed=fixed)


def physical_check(values: dict, boom_length: float | None = None, rel_tol: float = 0.2) -> list[str]:
    """Reasons why identified groups are not physically consistent (empty list = consistent).

    Checks every group >= 0 and, when the boom length is known, that l_b m / m and
    l_b^2 m_b / (l_b m_b) reproduce it within ``rel_tol``.
    """
    bad = [f"{k} = {v:.4g} < 0" for k, v in values.items() if k in PARAM_GROUPS and v < 0]
    if boom_length:
        for num, den in (("lb_m", "m"), ("lb2_mb", "lb_mb")):
            if num in values and den in values and values[den] > 0:
                lb = values[num] / values[den]
                if abs(lb - boom_length) > rel_tol * boom_length:
                    bad.append(f"{num}/{den} = {lb:.3g} m, boom length is {boom_length:.3g} m")
    return bad
