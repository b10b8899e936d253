"""The workbench verbs as library functions (what ``cablelab compare/diagnose/identify`` print).

Each takes a plant :class:`~cablelab.dataset.Dataset` and a :class:`~cablelab.model.Model` and
returns a typed result whose ``to_json()`` is the verb's JSON (CONTRACT section 5):
:func:`compare` a :class:`~cablelab.results.Comparison`, :func:`identify_report` an
:class:`~cablelab.results.IdentifyReport`, :func:`diagnose` a
:class:`~cablelab.diagnose.result.Diagnosis`. :func:`load` turns a bag (+ optional description
file) into (plant, description, dataset), :func:`build_model` a plant's baseline plus
``--effects`` into a model.
"""
from __future__ import annotations

import dataclasses
from typing import Mapping, Sequence

import numpy as np

from .dataset import Dataset
from .diagnose import cv_error, greedy, rank_candidates, worst_segments
from .diagnose.fit_metrics import fit_metrics
from .diagnose.ranking import ALPHA, FOLDS, MIN_GAIN
from .diagnose.result import Diagnosis
from .errors import CablelabError
from .fit import identify as _identify
from .fit.threads import blas_single
from .model import Model
from .plant_interface import DatasetOptions
from .results import Comparison, FitQuality, IdentifyReport


def load(bag_path, description_path=None, options: DatasetOptions | Mapping | None = None):
    """Open a bag, read its description (or the given file), check the plant's topics and build
    the plant's dataset (:func:`load_checked` without its check report).

    ``options``: a :class:`~cablelab.plant_interface.DatasetOptions`, or a mapping of its fields
    and the plant's own options (``{"conditioning": ..., "tensions": "motor"}``,
    :meth:`DatasetOptions.build`); None: the defaults.

    Returns:
        ``(plant, description, dataset)``.
    Raises:
        CablelabError: unreadable bag, no description, missing topics (one line each).
    """
    plant, desc, ds, _ = load_checked(bag_path, description_path, options)
    return plant, desc, ds


def load_checked(bag_path, description_path=None, options: DatasetOptions | Mapping | None = None, *,
                 recover: bool = False, before_dataset=None, limits=None):
    """:func:`load` with the input checks of :mod:`cablelab.bagcheck`: time base of every topic
    the plant reads (gaps, clock jumps, stamps out of order, NaN samples), description vs bag
    (joint and cable names), negative cable tensions. Samples inside a gap (widened by the
    conditioning border) are marked invalid in ``dataset.valid``: fits use the contiguous
    segments and never values interpolated across a gap. Samples where an actuator is inside its
    zero-speed zone are marked invalid for every plant with joint or winch actuators (capability
    ``*_actuators``; :func:`cablelab.velocity.exclude_zero_speed`).

    Args:
        recover: read an unfinished bag (recorder killed) up to its last complete chunk.
        before_dataset: optional ``fn(plant)`` called once the plant is known, before any data
            is read (e.g. refusing options of another plant).
        limits: :class:`~cablelab.timebase.Limits` of the time-base checks (default: the
            defaults; ``Limits(time_unit="s")`` trusts integer stamps as seconds).
    Returns:
        ``(plant, description, dataset, check)``, ``check`` a :class:`~cablelab.bagcheck.BagCheck`
        (``check.warnings``: lines for the text output and the JSON ``"warnings"`` list).
    Raises:
        CablelabError: unreadable bag, no description, missing topics, stamps going back in time,
            a description that does not match the bag (one line each).
    """
    from .bagcheck import check_bag
    from .bags import open_bag
    from .registry import get_plant

    bag = open_bag(bag_path, recover=recover)
    desc = load_bag_description(bag_path, description_path, bag)
    plant = get_plant(desc.plant)
    if before_dataset is not None:
        before_dataset(plant)
    for topic, msgtype in plant.topics:
        if not bag.has(topic):
            have = ", ".join(sorted(bag.topics)) or "none"
            raise CablelabError(f"{bag_path}: topic {topic} needed by plant {plant.name} is not in the "
                                f"bag (topics: {have})")
        bag.require(topic, msgtype)
    from .timebase import Limits

    options = DatasetOptions.build(plant, options)
    check = check_bag(bag, plant, desc, options, limits or Limits())
    ds = plant.dataset(bag, desc, dataclasses.replace(options, derived_velocity=check.derived_velocity))
    check.warnings.extend(ds.signals.get("load_warnings") or ())   # e.g. too slow for its motion
    # drives that stop: every plant with friction-bearing actuators (joint or winch drives)
    # leaves its zero-speed zone out of the fits (cablelab.velocity; a plant may have applied it
    # itself with its encoder's floor). Swing modes or a hopping body are not drives: untouched.
    from .velocity import exclude_zero_speed

    drives = any(c.endswith("_actuators") for c in plant.capabilities)
    if drives and "zero_speed_zone" not in ds.signals:
        ds = exclude_zero_speed(ds)
    if check.gaps:
        border = options.conditioning.border
        period = min(r.period for r in check.reports.values() if np.isfinite(r.period))
        keep = check.mask(ds.t, border * period)
        ds.valid = np.asarray(ds.valid, dtype=bool) & keep
        if ds.valid.sum() < 10:
            raise CablelabError(f"{bag_path}: fewer than 10 samples left outside the gaps of the recording")
    return plant, desc, ds, check


def load_bag_description(bag_path, description_path=None, bag=None):
    """The plant description of a run: the given file, else ``/plant_description`` in the bag
    (``bag``: the already opened bag, else it is opened).

    Raises:
        CablelabError: unreadable file or bag, or no description in the bag (one line).
    """
    from .description import load_description

    if description_path:
        return load_description(description_path)
    if bag is None:
        from .bags import open_bag

        bag = open_bag(bag_path)
    if bag.description is None:
        raise CablelabError(f"{bag_path}: no /plant_description in the bag; give --description FILE")
    return bag.description


def build_model(plant, desc, effects: Sequence[str] = (), baseline: Sequence[str] | None = None,
                fixed: dict | None = None, *, strict: bool = False) -> Model:
    """``baseline`` (default: the plant's nominal effects) + ``effects``, with known parameters.
    A parameter the data do not excite is held at its description (or neutral) value with a
    warning; ``strict`` refuses the rank-deficient fit instead (``--strict``)."""
    base = tuple(plant.baseline(desc)) if baseline is None else tuple(baseline)
    effs = base + tuple(e for e in effects if e not in base)
    return Model(plant.name, effs, dict(fixed or {}), unexcited="raise" if strict else "hold")


def _effect_table(ident) -> dict:
    return {row["name"]: {"value": row["value"], "stderr": row["stderr"], "unit": row["unit"],
                          "fixed": row["fixed"], **({"held": True} if row.get("held") else {})}
            for row in ident.table()}


@blas_single
def compare(ds: Dataset, model: Model, *, segments: int = 5) -> Comparison:
    """Inverse-model comparison: fit on the whole record, metrics per channel, worst segments,
    residual by regime and whiteness. ``.to_json()`` is CONTRACT section 5 (``compare``) + extras."""
    ident = _identify(model, ds)
    m = fit_metrics(ds, ident)
    plant = _plant_of(ds)
    free_run = plant.simulate(ds, ident.params) if plant is not None and plant.simulate is not None \
        else None
    return Comparison(
        plant=ds.plant, effects=list(model.effects), samples=int(ident.valid.sum()),
        channels=dict(zip(ds.channels, m.channels)),
        worst_segments=worst_segments(ds.t, ident.residual, m.y_meas, ds.channels, count=segments),
        params=_effect_table(ident), regimes=m.regimes,
        whiteness={ch: _whiteness_summary(w) for ch, w in m.whiteness.items()},
        rank=ident.linear.rank, condition=ident.linear.cond, held=ident.held,
        held_warning=ident.held_warning(), free_run=free_run, fit=ident)


def _plant_of(ds: Dataset):
    from .registry import get_plant

    try:
        return get_plant(ds.plant)
    except CablelabError:
        return None


def _whiteness_summary(w: dict) -> dict:
    """The JSON summary of one channel's :func:`~cablelab.diagnose.whiteness.whiteness`."""
    return {"band": w["band"], "white": w["white"], "autocorr_outside": w["outside"],
            "decimate": w["decimate"],
            "autocorr_lag1": w["autocorr"][1] if len(w["autocorr"]) > 1 else None,
            "cross": {k: {"outside": v["outside"], "uncorrelated": v["uncorrelated"],
                          "max_abs": float(np.max(np.abs(v["xcorr"])))} for k, v in w["cross"].items()}}


def _mean_nrmse(mets) -> float | None:
    """Mean NRMSE over the channels that have one (a channel without signal, e.g. a yaw the
    plant sets aside as not excited, has none)."""
    vals = [m["nrmse"] for m in mets if m.get("nrmse") is not None]
    return float(np.mean(vals)) if vals else None


@blas_single
def identify_report(ds: Dataset, model: Model, *, folds: int = FOLDS, simulation: str | None = None,
                    quiet: bool = True) -> IdentifyReport:
    """Identified parameters with standard errors, rank/condition, in-sample and held-out fit
    (what ``cablelab identify`` prints; the fit itself is :func:`cablelab.fit.identify`).

    With ``simulation`` (``"nmse"`` or ``"pearson"``) the inverse-model result starts a
    simulation-based fit of the plant (if it offers one), reported under ``"simulation"``."""
    ident = _identify(model, ds)
    mets = fit_metrics(ds, ident, with_regimes=False, with_whiteness=False).channels
    cv = cv_error(model, ds, folds)[0] if folds else None
    quality = FitQuality(nrmse=_mean_nrmse(mets), cv_nrmse=cv, folds=folds,
                         channels=dict(zip(ds.channels, mets)), rank=ident.linear.rank,
                         parameters=len(ident.linear.names), condition=ident.linear.cond,
                         unidentifiable=ident.linear.unidentifiable,
                         active_bounds=ident.linear.active_bounds)
    # the parameters in the user's terms; the regression's own coefficients they replace
    # (e.g. c_td, c_lo for beta_td, beta_lo) under "internal"
    params, internal = ident.reported(ds)
    sim = None
    if simulation:
        plant = _plant_of(ds)
        if plant is None or plant.simulation_fit is None:
            raise CablelabError(f"plant {ds.plant} offers no simulation-based fit")
        sf = plant.simulation_fit(ds, ident.params, objective=simulation, progress=not quiet)
        sim = {"objective": sf.objective, "nmse": sf.nmse, "pearson": sf.pearson,
               "iterations": sf.iterations, "evaluations": sf.evaluations,
               "params": {k: {"value": v, "stderr": sf.stderr[k]} for k, v in sf.params.items()}}
    return IdentifyReport(plant=ds.plant, effects=list(model.effects), samples=int(ident.valid.sum()),
                          params=params, quality=quality, held=ident.held,
                          held_warning=ident.held_warning(), internal=internal, simulation=sim,
                          fit=ident)


@blas_single
def diagnose(ds: Dataset, model: Model, candidates: Sequence[str], *, folds: int = FOLDS,
             alpha: float = ALPHA, min_gain: float = MIN_GAIN, greedy_mode: bool = False,
             quiet: bool = True) -> Diagnosis:
    """Rank the missing effects (CONTRACT section 5 ``diagnose``); with ``greedy_mode`` also the
    waterfall of significant effects added one at a time. ``.to_json()`` is the contract JSON."""
    from .datachecks import check_dataset

    from .diagnose import fold_indices

    fold_indices(ds.n, folds)  # too short for the folds: that message first
    check_dataset(ds)  # bad input: a one-line refusal, never a confident ranking
    cands = [c for c in candidates if c not in model.effects]
    if greedy_mode:
        steps = greedy(model, ds, cands, folds=folds, alpha=alpha, min_gain=min_gain, quiet=quiet)
        first = steps[0]
        return Diagnosis(plant=ds.plant, baseline_effects=first.effects, baseline_error=first.error,
                         ranking=first.ranking, folds=folds, greedy=steps, held=first.fit.held,
                         held_warning=first.fit.held_warning(), alpha=alpha, min_gain=min_gain,
                         model=model, fit=first.fit)
    return rank_candidates(model, ds, cands, folds=folds, alpha=alpha, min_gain=min_gain, quiet=quiet)
