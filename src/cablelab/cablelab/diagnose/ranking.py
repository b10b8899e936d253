"""Which effect is missing: held-out error of every candidate, significance, greedy waterfall.

For each applicable catalog effect not yet in the model, the model is refitted with it and its
error measured on held-out data by blocked k-fold cross-validation over time (contiguous test
blocks, a guard band around each so filter transients do not leak). Candidates are ranked by
held-out error. A candidate is *significant* when

1. it removes at least ``MIN_GAIN`` (5 %) of the model's held-out error on the channels it
   changes (:func:`~cablelab.diagnose.score.practical_gain`; practical significance: smaller
   gains are reported with their p-value but not worth a new physical effect; on EMPS a -0.3 ms
   "delay", a third of a sample, gains 3 % and is left out) without raising the error over all
   channels, and
2. a nested-model F-test on the full-data fits rejects "no gain" at ``alpha / m`` (Bonferroni over
   the m candidates), with the sample count replaced by the effective number of independent
   samples ``n_eff = n (1 - r1) / (1 + r1)`` (r1 = lag-1 autocorrelation of the residual; a
   filtered, oversampled residual is far from white and would otherwise make every effect
   "significant"). The BIC difference on ``n_eff`` is reported alongside.

The greedy mode adds the best significant candidate, re-ranks, and stops when none is
significant; its steps are the waterfall baseline -> +effect 1 -> +effect 2.
"""
from __future__ import annotations

import sys
import time

import numpy as np
import scipy.stats

from ..effects import get_effect
from ..errors import CablelabError
from ..fit import evaluate, identify
from ..fit.identification import lag1_autocorrelation
from ..fit.threads import blas_single
from ..dataset import Dataset
from ..model import Model
from .localise import derived_regimes, factorise_regimes, residual_by_regime
from .result import Candidate, Diagnosis, Step
from .score import ALPHA, MIN_GAIN, channel_nrmse, heldout_error, lr_significance, practical_gain

#: default number of folds, guard band (fraction of samples per side); the significance level
#: and the minimum held-out gain are the score's (:data:`.score.ALPHA`, :data:`.score.MIN_GAIN`)
FOLDS = 5
GUARD_FRACTION = 0.01
#: minimum samples per test block
MIN_FOLD_SAMPLES = 50


def fold_indices(n: int, k: int = FOLDS, guard: int | None = None) -> list[tuple[np.ndarray, np.ndarray]]:
    """Blocked k-fold split of ``n`` time samples: ``[(train_idx, test_idx)]``.

    Each test block is contiguous; ``guard`` samples either side of it are left out of training.

    Raises:
        CablelabError: too few samples for ``k`` folds.
    """
    if k < 2:
        raise CablelabError(f"--folds {k}: need at least 2 folds")
    if n < k * MIN_FOLD_SAMPLES:
        raise CablelabError(f"only {n} samples for {k} folds (need at least {k * MIN_FOLD_SAMPLES}): "
                            "use fewer --folds or a longer recording")
    guard = int(round(GUARD_FRACTION * n)) if guard is None else int(guard)
    edges = np.linspace(0, n, k + 1).astype(int)
    idx = np.arange(n)
    out = []
    for i in range(k):
        a, b = edges[i], edges[i + 1]
        test = idx[a:b]
        train = idx[(idx < a - guard) | (idx >= b + guard)]
        out.append((train, test))
    return out


def cv_error(model: Model, ds: Dataset, folds: int = FOLDS, start: dict | None = None
             ) -> tuple[float, np.ndarray, np.ndarray]:
    """Held-out error of a model (blocked k-fold): the geometric mean over channels of the
    per-channel NRMSE (:func:`~cablelab.diagnose.score.heldout_error`; one channel: the NRMSE). ``start``: nonlinear parameter values to start
    each fold's outer search from (the full-record fit), instead of a grid.

    Returns:
        ``(error, y_meas (N, C), y_hat (N, C))`` with the held-out predictions of every sample
        (NaN where not valid).
    """
    y_meas = np.full_like(ds.y, np.nan)
    y_hat = np.full_like(ds.y, np.nan)
    for train, test in fold_indices(ds.n, folds):
        r = identify(model, ds.subset(train), start=start)
        ym, yh, ok = evaluate(model, ds.subset(test), r.params)
        ym = np.where(ok[:, None], ym, np.nan)
        y_meas[test], y_hat[test] = ym, yh
    ok = np.isfinite(y_meas).all(axis=1) & np.isfinite(y_hat).all(axis=1)
    return heldout_error(y_meas, y_hat, ok), y_meas, y_hat


def _n_params(ident) -> int:
    return len(ident.params) - len(ident.fixed)


def significance(base, cand, n_candidates: int = 1, alpha: float = ALPHA) -> dict:
    """Nested F-test and BIC of a candidate fit against the base fit (full data).

    Args:
        base, cand: :class:`~cablelab.fit.Identification` of the model without / with the effect.
    Returns:
        ``{"p_value", "f", "n_eff", "delta_bic", "passes"}`` (passes: p < alpha / n_candidates).
    """
    rss0, rss1 = base.linear.rss, cand.linear.rss
    n = cand.linear.n
    step = int(cand.extra.get("sample_step", 1))  # parallel-filtered data: fs / (2 f_c)
    r1 = lag1_autocorrelation(cand.residual, step)
    n_eff = max(n / step * (1.0 - r1) / (1.0 + r1), 3.0)
    p0, p1 = _n_params(base), _n_params(cand)
    dp = max(p1 - p0, 1)
    dof = max(n_eff - p1, 1.0)
    # both RSS scale by n_eff / n, which cancels in the ratio: only the dof change
    f = ((rss0 - rss1) / dp) / (rss1 / dof) if rss1 > 0 else np.inf
    p_value = float(scipy.stats.f.sf(f, dp, dof)) if np.isfinite(f) else 0.0
    delta_bic = float(n_eff * np.log(max(rss1, 1e-300) / max(rss0, 1e-300)) + dp * np.log(n_eff))
    return {"p_value": p_value, "f": float(f), "n_eff": float(n_eff), "delta_bic": delta_bic,
            "passes": bool(p_value < alpha / max(n_candidates, 1))}


def _evidence(before: list[dict], after: list[dict], min_share: float = 0.02) -> dict | None:
    """The regime label (holding at least ``min_share`` of the samples) where adding the effect
    lowers the residual mean square most: where the effect's signature lives."""
    if not before:
        return None
    total = max(r["n"] for r in before) or 1
    after_by = {(r["regime"], r["label"], r["channel"]): r for r in after}
    best, best_drop = None, 0.0
    for r in before:
        a = after_by.get((r["regime"], r["label"], r["channel"]))
        if a is None or r["nrmse"] is None or a["nrmse"] is None:
            continue
        n_regime = sum(x["n"] for x in before if x["regime"] == r["regime"] and x["channel"] == r["channel"])
        if r["n"] < min_share * max(n_regime, total):
            continue
        drop = r["nrmse"] ** 2 - a["nrmse"] ** 2
        if drop > best_drop:
            best_drop = drop
            best = {"regime": r["regime"], "label": r["label"], "channel": r["channel"],
                    "before": r["nrmse"], "after": a["nrmse"]}
    return best


def _fmt(v: float, s: float) -> str:
    if s > 0 and np.isfinite(s):
        digits = max(0, int(-np.floor(np.log10(s))) + 1)
        digits = min(digits, 8)
        return f"{v:.{digits}f} +- {s:.{digits}f}"
    return f"{v:.4g}"


def explain(effect_id: str, params: dict, stderr: dict, units: dict, before: float,
            after: float, significant: bool, changed: tuple[int, int] | None = None,
            gain_changed: float | None = None) -> str:
    """One sentence: residual signature, fitted parameters and how much of the error they remove.
    ``changed``: (channels the effect changes, channels) and ``gain_changed`` the relative drop on
    those, when it changes only some of them."""
    eff = get_effect(effect_id)
    ptxt = ", ".join(f"{k} = {_fmt(v, stderr.get(k, 0.0))} {units.get(k, '')}".rstrip()
                     for k, v in params.items())
    gain = 100.0 * (1.0 - after / before) if before > 0 else 0.0
    name = effect_id.replace("_", " ")
    part = ""
    if changed is not None and gain_changed is not None and 0 < changed[0] < changed[1]:
        part = (f" ({100.0 * gain_changed:.0f} % on the {changed[0]} of {changed[1]} channels it "
                "changes)")
    if significant:
        return f"{eff.signature}; {name} {ptxt} removes {gain:.0f} % of the held-out error{part}"
    return (f"{name} ({ptxt}) changes the held-out error by {-gain:+.1f} %{part}: "
            "not significant beyond noise and its added parameters")


class _Progress:
    """Periodic progress line with ETA on stderr (only for runs longer than a few seconds)."""

    def __init__(self, total: int, label: str, quiet: bool = False):
        self.total, self.label, self.quiet = total, label, quiet
        self.t0 = time.monotonic()
        self.last = self.t0
        self.done = 0

    def step(self, what: str = "") -> None:
        self.done += 1
        now = time.monotonic()
        if self.quiet or now - self.last < 2.0:
            return
        self.last = now
        eta = (now - self.t0) / self.done * (self.total - self.done)
        print(f"[{self.label}] {self.done}/{self.total} {what} - ETA {eta:.0f} s",
              file=sys.stderr, flush=True)


def _fitted_candidate(c: str, ds: Dataset, base_full, full, before: tuple, after: tuple,
                      n_candidates: int, alpha: float, min_gain: float, own_held: list,
                      regime_ref: tuple) -> tuple[Candidate, dict]:
    """The ranking row of a candidate that could be fitted, and its own parameters by name.

    Args:
        base_full, full: the full-record fits without / with the candidate.
        before, after: ``(held-out error, y_meas, y_hat)`` without / with it (:func:`cv_error`).
        n_candidates: the Bonferroni count; own_held: its parameters held as not excited.
        regime_ref: ``(residual by regime without it, y_ref, regimes)`` for its evidence.
    """
    err0, ym0, yh0 = before
    err1, ym1, yh1 = after
    by_regime0, y_ref, regimes = regime_ref
    sig = lr_significance(base_full, full, n_candidates, alpha)
    gain, changed = practical_gain(ym0, yh0, ym1, yh1)
    significant = bool(sig["passes"] and gain >= min_gain and err1 < err0)
    own = full.effect_params(c, ds)
    # reported in the user's terms (the paper's / spec's parameters, errors propagated);
    # the regression's own coefficients stay under "internal"
    phys = full.physical(c, ds)
    inner = full.internal(c, ds)
    from .identifiability import confounding, describe

    confound = confounding(full, list(own))
    significant = significant and bool(confound["identifiable"])
    row = Candidate(c, err0, err1, params={k: v["value"] for k, v in phys.items()},
                    significant=significant,
                    stderr={k: v["stderr"] for k, v in phys.items()},
                    units={k: v["unit"] for k, v in phys.items()},
                    p_value=sig["p_value"], delta_bic=sig["delta_bic"], n_eff=sig["n_eff"],
                    gain=gain, channels=dict(zip(ds.channels, map(float, channel_nrmse(ym1, yh1)))),
                    evidence=_evidence(by_regime0, residual_by_regime(full.residual, y_ref,
                                                                      regimes, ds.channels)),
                    identifiability=confound, held=own_held or None,
                    internal={k: v["value"] for k, v in inner.items()} or None)
    row.explanation = explain(c, row.params, row.stderr, row.units, err0, err1, significant,
                              (int(changed.sum()), len(changed)), gain)
    if significant and row.evidence:
        where = row.evidence
        row.explanation += (f"; largest drop where {where['regime']} is {where['label']} "
                            f"({100 * where['before']:.0f} % -> {100 * where['after']:.0f} % of "
                            f"the {where['channel']} RMS)")
    row.explanation += describe(confound)
    return row, own


@blas_single
def rank_candidates(model: Model, ds: Dataset, candidates, *, folds: int = FOLDS,
                    alpha: float = ALPHA, min_gain: float = MIN_GAIN, quiet: bool = True) -> Diagnosis:
    """Rank candidate effects by held-out error when added to ``model``.

    Args:
        model: the analysed model; ds: its dataset.
        candidates: effect ids to try (those already in the model are skipped).
        folds: k of the blocked k-fold; alpha: family-wise significance level; min_gain: minimum
            relative held-out error reduction.
    Returns:
        :class:`~cablelab.diagnose.result.Diagnosis` with ``ranking`` (:class:`Candidate` s)
        sorted by held-out error after (best first), ``fit`` the model's own fit.
    """
    cands = [c for c in dict.fromkeys(candidates) if c not in model.effects]
    for c in cands:
        get_effect(c, model.plant)
    fold_indices(ds.n, folds)  # fail early on too few samples
    prog = _Progress(len(cands) + 1, "diagnose", quiet)
    base_full = identify(model, ds)
    err0, ym0, yh0 = cv_error(model, ds, folds, start=base_full.params)
    regimes = factorise_regimes(derived_regimes(ds))
    y_ref = base_full.residual + base_full.y_hat
    by_regime0 = residual_by_regime(base_full.residual, y_ref, regimes, ds.channels)
    prog.step("baseline")
    # what the ambiguity check compares (diagnose/ambiguity.py): the model's columns, weighted and
    # on its valid rows, and each candidate's held-out prediction and projected columns
    from .ambiguity import find_ambiguous, project_out
    from ..fit.linear import weigh

    ev_base = model.evaluate(ds, base_full.params)
    ds_base = ev_base.ds
    w_ch = base_full.linear.channel_scale if base_full.linear.channel_scale is not None \
        else np.ones(ds.n_channels)
    use = base_full.valid & np.isfinite(ds_base.y).all(axis=1)

    def weighted(phi):
        return weigh(w_ch, phi)[use].reshape(int(use.sum()) * phi.shape[1], phi.shape[2])

    phi0 = weighted(ev_base.phi)
    compared = {}
    rows = []
    for c in cands:
        m2 = model.with_effect(c)
        try:
            full = identify(m2, ds)
            err1, ym1, yh1 = cv_error(m2, ds, folds, start=full.params)
        except CablelabError as exc:  # e.g. the effect is not excited: rank-deficient
            rows.append(Candidate(c, err0, None, explanation=f"{c}: cannot be fitted ({exc})"))
            prog.step(c)
            continue
        own_held = [k for k in full.held if k not in base_full.held]
        if own_held and set(own_held) >= {p.name for p in get_effect(c).columns(ds)}:
            rows.append(Candidate(c, err0, err1, held=own_held,
                                  explanation=f"{c}: not excited by this recording "
                                              f"({', '.join(own_held)} cannot be determined from it)"))
            prog.step(c)
            continue
        row, own = _fitted_candidate(c, ds, base_full, full, (err0, ym0, yh0), (err1, ym1, yh1),
                                     len(cands), alpha, min_gain, own_held,
                                     (by_regime0, y_ref, regimes))
        rows.append(row)
        ev_c = m2.evaluate(ds, base_full.params)
        phi_c, cols_c = ev_c.phi, ev_c.columns
        own_idx = [i for i, p in enumerate(cols_c) if p.name in own]
        compared[c] = {"error": err1, "y": ym1, "y_hat": yh1, "y_hat0": yh0,
                       "columns": project_out(phi0, weighted(phi_c[:, :, own_idx]))}
        prog.step(c)
    rows.sort(key=lambda r: (r.error_after is None, r.error_after if r.error_after is not None else 0))
    helps = [r.effect for r in rows if r.error_after is not None
             and (r.significant or (r.gain or 0.0) >= min_gain)]
    rms = np.sqrt(np.nanmean(np.where(use[:, None], ds_base.y, np.nan) ** 2, axis=0))
    pairs = find_ambiguous(err0, compared, helps, 1.0 / np.where(rms > 0, rms, 1.0))
    from .ambiguity import describe as describe_ambiguity

    for r in rows:
        others = pairs.get(r.effect)
        if others:
            r.ambiguous_with = [o.effect for o in rows if o.effect in others]
            r.ambiguity = {o: others[o] for o in r.ambiguous_with}
            r.explanation += describe_ambiguity(r.effect, r.ambiguous_with)
    return Diagnosis(plant=model.plant, baseline_effects=list(model.effects), baseline_error=err0,
                     ranking=rows, folds=folds, held=base_full.held,
                     held_warning=base_full.held_warning(), alpha=alpha, min_gain=min_gain,
                     model=model, fit=base_full)


@blas_single
def greedy(model: Model, ds: Dataset, candidates, *, folds: int = FOLDS, alpha: float = ALPHA,
           min_gain: float = MIN_GAIN, max_steps: int = 10, quiet: bool = True) -> list[Step]:
    """Add the best significant candidate until none is significant (the waterfall).

    Returns:
        :class:`~cablelab.diagnose.result.Step` list: step 0 is the model as given, each further
        step adds one effect; the last step's ranking shows that no remaining candidate is
        significant.
    """
    steps = []
    current = model
    added = note = None
    for _ in range(max_steps + 1):
        d = rank_candidates(current, ds, candidates, folds=folds, alpha=alpha, min_gain=min_gain,
                            quiet=quiet)
        fit = d.fit
        steps.append(Step(effects=list(current.effects), added=added, error=d.baseline_error,
                          params=dict(fit.params), stderr=dict(fit.stderr), units=dict(fit.units),
                          ranking=d.ranking, note=note, fit=fit))
        best = d.best_significant()
        if best is None:
            break
        added = best.effect
        rivals = list(best.ambiguous_with or ())
        note = (f"chose {added} over {', '.join(rivals)} (ambiguous: held-out errors equal within "
                "noise, this recording cannot tell them apart)") if rivals else None
        current = current.with_effect(added)
    return steps
