"""Identifiability of a candidate effect: can the data tell its parameters from the others?

When two candidates explain the same residual (Coulomb vs viscous friction with few speed levels,
a sensor offset vs gravity at one pose, Coulomb vs offset when the drive only moves one way), the
least-squares estimates are strongly correlated. The correlation of two estimates is read from the
LS covariance ``sigma^2 (Phi^T Phi)^-1`` (002 sec. 5.3: the condition number of the scaled
regressor is its global measure): ``rho_ij = C_ij / sqrt(C_ii C_jj)``. Above
:data:`CONFOUNDED` the ranking says so and names the experiment that would separate them; above
:data:`UNIDENTIFIABLE` *and* with an estimate smaller than :data:`MIN_T` standard errors the effect
is not called significant (the data cannot attribute the gain to it). A high correlation alone is
not enough: with enough data two correlated estimates can both be precise (001: r_p and m).
"""
from __future__ import annotations

import numpy as np

#: |correlation| of two estimates reported as confounded, and treated as unidentifiable
CONFOUNDED, UNIDENTIFIABLE = 0.9, 0.99
#: |estimate| / standard error below which a confounded estimate counts as not determined
MIN_T = 5.0

#: (parameter name stem, other stem) -> the recording that separates them
_EXPERIMENTS = [
    ({"Fc", "Fv"}, "moves at several constant speed levels spread over the speed range"),
    ({"Fc", "OF"}, "moves in both directions (the sign of the velocity must change)"),
    ({"OF", "mc"}, "motion through (or holds at) several poses spread over the angle range"),
    ({"OF", "m"}, "motion through several poses / loads"),
    ({"Fv", "M"}, "moves with different accelerations at the same speeds (chirps or faster ramps)"),
    ({"Fc", "M"}, "moves with different accelerations at the same speeds (chirps or faster ramps)"),
]


def _stem(name: str) -> str:
    return name.split("[", 1)[0]


def suggest_experiment(a: str, b: str) -> str:
    """The recording that would separate parameters ``a`` and ``b`` (names, ``Fc[winch_1]`` ok)."""
    pair = {_stem(a), _stem(b)}
    for stems, text in _EXPERIMENTS:
        if pair == stems:
            return text
    return f"a recording that excites {a} and {b} independently (different motion patterns)"


def correlations(ident) -> tuple[tuple[str, ...], np.ndarray]:
    """Names and correlation matrix of the free linear estimates of an identification."""
    lin = ident.linear
    cov = np.asarray(lin.cov, dtype=float)
    d = np.sqrt(np.clip(np.diag(cov), 0, None))
    with np.errstate(invalid="ignore", divide="ignore"):
        corr = cov / np.outer(d, d)
    return tuple(lin.names), np.nan_to_num(corr)


def confounding(ident, own: list[str], threshold: float = CONFOUNDED) -> dict:
    """``{"condition", "confounded": [{"param", "with", "correlation", "experiment"}],
    "identifiable"}`` of the effect's own parameters ``own`` within the fitted model."""
    names, corr = correlations(ident)
    out = []
    for p in own:
        if p not in names:
            continue
        i = names.index(p)
        for j, q in enumerate(names):
            if q in own or abs(corr[i, j]) < threshold:
                continue
            out.append({"param": p, "with": q, "correlation": float(corr[i, j]),
                        "experiment": suggest_experiment(p, q)})
    out.sort(key=lambda r: -abs(r["correlation"]))

    def vague(p):
        se = float(ident.stderr.get(p, 0.0))
        return se > 0 and abs(float(ident.params.get(p, 0.0))) < MIN_T * se

    # a per-actuator effect is identified through any of its parameters the data determine
    # (one excited winch or cable joint): it is unidentifiable only when confounded parameters
    # are all it has
    bad = {r["param"] for r in out if abs(r["correlation"]) >= UNIDENTIFIABLE and vague(r["param"])}
    determined = [p for p in own if p in names and p not in bad and not vague(p)
                  and abs(float(ident.params.get(p, 0.0))) > 0]
    return {"condition": float(ident.linear.cond), "confounded": out,
            "identifiable": not bad or bool(determined)}


def describe(info: dict) -> str:
    """One clause for the explanation ('' when nothing is confounded)."""
    if not info["confounded"]:
        return ""
    r = info["confounded"][0]
    return (f"; {r['param']} and {r['with']} are confounded in this recording (correlation "
            f"{r['correlation']:+.2f}, condition {info['condition']:.3g}): to separate them record "
            f"{r['experiment']}")
