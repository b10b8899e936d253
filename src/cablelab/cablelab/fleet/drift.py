"""Drift of identified parameters over a fleet's time line: a change-point / trend test with
significance, corrected for testing many machines, parameters and change times.

For one series (one machine, effect and parameter; bags ordered by start time, values y_i at
times t_i in days) the null model is a constant, y_i = c + e_i. Two alternatives are fitted by
ordinary least squares for every admissible change index k:

* step (a sensor offset appears, a base settles): y_i = c + d [i >= k], at least 2 bags each side;
* trend from a hinge (wear): y_i = c + b max(0, t_i - t_{k-1}), at least 2 bags after the hinge;
  k = 1 is a trend over the whole campaign.

Each is a nested linear model with one extra parameter, so with unknown noise variance
F_k = (RSS_0 - RSS_k) / (RSS_k / (n - 2)) ~ F(1, n - 2) under the null (Gaussian, independent
bags). The series' p-value is the smallest p_k times the number of alternatives tried
(Bonferroni over change times and kinds); across series Holm's step-down procedure keeps the
family-wise error rate at ``alpha``. ``since`` is the start time of bag k, the first bag after
the change. Noise variance is estimated from the series itself, so identification standard
errors that are too small (coloured residuals) cannot make a constant series look drifting.
"""
from __future__ import annotations

import dataclasses
import datetime as _dt
import json

import numpy as np

ALPHA = 0.01
MIN_BAGS = 6


@dataclasses.dataclass
class Series:
    """One machine's parameter over time (values and standard errors in the parameter's unit)."""

    machine: str
    effect: str
    param: str
    time: list  # datetime (UTC) per bag, sorted
    value: np.ndarray
    stderr: np.ndarray
    bags: list


@dataclasses.dataclass
class ChangePoint:
    """Best change of a series: ``kind`` step|trend, first changed bag index ``k``, F statistic,
    raw p (best k) and Bonferroni p (over the ``tries`` alternatives), fitted values."""

    kind: str
    k: int
    f: float
    p_raw: float
    p: float
    tries: int
    fit: np.ndarray


@dataclasses.dataclass
class Finding:
    machine: str
    effect: str
    param: str
    since: _dt.datetime
    kind: str
    p_value: float
    before: float
    after: float
    bag: str


def _rss(X: np.ndarray, y: np.ndarray):
    coef, *_ = np.linalg.lstsq(X, y, rcond=None)
    fit = X @ coef
    return float(np.sum((y - fit) ** 2)), fit


def change_point(t_days: np.ndarray, y: np.ndarray) -> ChangePoint | None:
    """The best step or hinge-trend change of one series (module docstring); None if the series
    is too short or constant."""
    from scipy import stats

    y = np.asarray(y, float)
    t = np.asarray(t_days, float)
    n = y.size
    if n < 4:
        return None
    rss0 = float(np.sum((y - y.mean()) ** 2))
    if rss0 <= 1e-24 * max(1.0, float(np.sum(y**2))):
        return None
    one = np.ones(n)
    cands = []
    for k in range(2, n - 1):  # step: >= 2 bags each side
        cands.append(("step", k, np.column_stack([one, (np.arange(n) >= k).astype(float)])))
    for k in range(1, n - 1):  # hinge at bag k-1: >= 2 bags after it
        cands.append(("trend", k, np.column_stack([one, np.maximum(0.0, t - t[k - 1])])))
    best = None
    for kind, k, X in cands:
        rss, fit = _rss(X, y)
        f = (rss0 - rss) / max(rss / (n - 2), 1e-300)
        if best is None or f > best[2]:
            best = (kind, k, f, fit)
    kind, k, f, fit = best
    p_raw = float(stats.f.sf(f, 1, n - 2))
    return ChangePoint(kind, k, float(f), p_raw, min(1.0, p_raw * len(cands)), len(cands), fit)


def series_from_rows(rows: list[dict], min_bags: int = MIN_BAGS) -> list[Series]:
    """Series per (machine, effect, parameter) from result rows (``status == "ok"``), for the
    effects that are in the model or significant in at least one bag of that machine."""
    relevant = set()
    groups: dict[tuple, list] = {}
    for r in rows:
        if r.get("status") != "ok" or not r.get("effect"):
            continue
        if r.get("in_model") or r.get("significant"):
            relevant.add((r["machine"], r["effect"]))
        try:
            params = json.loads(r.get("params") or "{}")
        except ValueError:
            continue
        for name, v in params.items():
            if v.get("value") is None or v.get("held"):   # held: not measured by this bag
                continue
            groups.setdefault((r["machine"], r["effect"], name), []).append(
                (r["start_time"], v["value"], v.get("stderr"), r["bag"]))
    out = []
    for (m, e, p), items in sorted(groups.items()):
        if (m, e) not in relevant or len(items) < min_bags:
            continue
        items.sort(key=lambda x: x[0])
        out.append(Series(m, e, p, [x[0] for x in items], np.array([x[1] for x in items], float),
                          np.array([np.nan if x[2] is None else x[2] for x in items], float),
                          [x[3] for x in items]))
    return out


def days(times) -> np.ndarray:
    t0 = times[0]
    return np.array([(t - t0).total_seconds() / 86400.0 for t in times])


def detect(series: list[Series], alpha: float = ALPHA) -> tuple[list[Finding], list[dict]]:
    """Drift findings (Holm-adjusted family-wise level ``alpha``) and the test of every series
    (``{"series", "change", "p_adjusted", "drift"}``)."""
    tests = []
    for s in series:
        cp = change_point(days(s.time), s.value)
        tests.append({"series": s, "change": cp, "p_adjusted": 1.0, "drift": False})
    order = sorted((i for i, x in enumerate(tests) if x["change"] is not None),
                   key=lambda i: tests[i]["change"].p)
    m = len(order)
    running = 0.0
    for rank, i in enumerate(order):
        running = max(running, min(1.0, (m - rank) * tests[i]["change"].p))
        tests[i]["p_adjusted"] = running
    stop = False
    findings = []
    for i in order:  # Holm: reject in order while adjusted p < alpha
        if stop or tests[i]["p_adjusted"] >= alpha:
            stop = True
            continue
        tests[i]["drift"] = True
        s, cp = tests[i]["series"], tests[i]["change"]
        findings.append(Finding(s.machine, s.effect, s.param, s.time[cp.k], cp.kind,
                                tests[i]["p_adjusted"], float(np.mean(s.value[:cp.k])),
                                float(s.value[-1]), s.bags[cp.k]))
    findings.sort(key=lambda f: (f.machine, f.effect, f.param))
    return findings, tests
