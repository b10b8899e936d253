"""One bag -> result rows (the unit of work of ``cablelab batch``). Never raises: a bag that
cannot be diagnosed gives one row whose ``status`` is the one-line reason.

The work is the library's own: :func:`cablelab.workbench.load`, :func:`~cablelab.workbench.build_model`,
:func:`~cablelab.workbench.diagnose` (held-out ranking, optional greedy waterfall; its fit of the
model gives the model's own parameters with standard errors). Optionally the bag's own
``cablelab report`` is written next to the results, from the same diagnosis when it is greedy.
"""
from __future__ import annotations

import datetime as _dt
import json
import os
import tempfile
import time

from .scan import BagRef, filesystem, is_local

FAILED_EFFECT = ""


def _one_line(exc: BaseException) -> str:
    text = str(exc).strip().splitlines()
    return text[0] if text else type(exc).__name__


def _params_json(values: dict, stderr: dict | None, names, held=()) -> str:
    """name -> {"value", "stderr"} (+ ``"held": true`` for a parameter the bag did not excite)."""
    stderr = stderr or {}
    return json.dumps({k: {"value": _f(values.get(k)), "stderr": _f(stderr.get(k)),
                           **({"held": True} if k in held else {})} for k in names if k in values})


def _f(v):
    try:
        v = float(v)
    except (TypeError, ValueError):
        return None
    return v if v == v and abs(v) != float("inf") else None


def _effect_names(effect_id: str, ds) -> list[str]:
    from ..effects import get_effect

    return [p.name for p in get_effect(effect_id, ds.plant).columns(ds)]


def _local(ref: BagRef):
    """(local path, temp dir or None): a remote bag is copied to a temp dir first."""
    fs, path = filesystem(ref.url)
    if is_local(fs):
        return path, None
    tmp = tempfile.mkdtemp(prefix="cablelab-bag-")
    dest = os.path.join(tmp, os.path.basename(path.rstrip("/")) or "bag")
    fs.get(path, dest, recursive=True)
    return dest, tmp


def run_bag(ref: BagRef, bag_hash: str, effects=(), greedy: bool = False, folds: int = 5,
            report_dir: str | None = None, strict: bool = False) -> list[dict]:
    """Diagnose one bag. Returns its rows (see :mod:`cablelab.fleet.table`); never raises.
    Parameters the bag does not excite are held at their description or neutral values, named
    in the rows' ``warnings`` and flagged ``held`` in ``params``; ``strict`` refuses such a bag
    instead (its one row's ``status`` is the refusal), as ``diagnose --strict``."""
    t0 = time.monotonic()
    base = {"bag": ref.rel, "url": ref.url, "bag_hash": bag_hash, "machine": ref.machine,
            "start_time": ref.start_time, "plant": None}
    try:
        rows = _rows(ref, base, effects, greedy, folds, report_dir, strict)
    except Exception as exc:  # noqa: BLE001 - every failure becomes a row
        from ..errors import CablelabError

        msg = _one_line(exc) if isinstance(exc, CablelabError) else f"{type(exc).__name__}: {_one_line(exc)}"
        rows = [dict(base, effect=FAILED_EFFECT, in_model=False, status=msg)]
    sec = time.monotonic() - t0
    for r in rows:
        r["seconds"] = sec
        if r["machine"] is None:
            r["machine"] = ""
    return rows


def _rows(ref, base, effects, greedy, folds, report_dir, strict=False):
    import shutil

    from ..effect_spec import parse_effect_list
    from ..workbench import build_model, diagnose, load

    path, tmp = _local(ref)
    try:
        plant, desc, ds = load(path)
        from ..bags import open_bag  # start time: first stamp of the bag

        start = base["start_time"]
        if start is None:
            start = _dt.datetime.fromtimestamp(open_bag(path).start, _dt.timezone.utc)
        base = dict(base, plant=plant.name, machine=base["machine"] or desc.name or "",
                    start_time=start)
        model = build_model(plant, desc, parse_effect_list(list(effects)), strict=strict)
        cands = plant.candidates(desc)
        d = diagnose(ds, model, cands, folds=folds, greedy_mode=greedy, quiet=True)
        first = {c.effect: (i, c) for i, c in enumerate(d.ranking)}
        if greedy:
            final_effects, final_error = list(d.final.effects), d.final.error
            fvals, ferr = d.final.params, d.final.stderr
            last = {c.effect: c for c in d.final.ranking}
            fit = d.final.fit
        else:
            fit = d.fit
            final_effects, final_error = list(model.effects), d.baseline_error
            reported = d.fit.reported(ds)[0]   # the model's parameters in the user's terms
            fvals = {k: v["value"] for k, v in reported.items()}
            ferr = {k: v["stderr"] for k, v in reported.items()}
            last = {c.effect: c for c in d.ranking}
        held = fit.held if fit is not None else dict(d.held)
        warning = fit.held_warning() if fit is not None else d.held_warning
        base = dict(base, warnings=warning)
        rows = []
        model_text = "+".join(final_effects)
        for eff in final_effects:
            rank, c = first.get(eff, (None, None))
            rows.append(dict(base, effect=eff, in_model=True, rank=rank,
                             significant=None if c is None else bool(c.significant),
                             error_before=d.baseline_error if c is None else c.error_before,
                             error_after=final_error if c is None else c.error_after,
                             p_value=None if c is None else c.p_value,
                             params=_params_json(fvals, ferr, _effect_names(eff, ds), held),
                             model=model_text, status="ok"))
        for eff, (rank, c) in first.items():
            if eff in final_effects:
                continue
            lc = last.get(eff, c)
            rows.append(dict(base, effect=eff, in_model=False, rank=rank, significant=bool(c.significant),
                             error_before=c.error_before, error_after=c.error_after, p_value=c.p_value,
                             params=_params_json(lc.params, lc.stderr, list(lc.params), lc.held or ()),
                             model=model_text, status="ok"))
        if report_dir:
            from ..report import build_report

            page_diagnosis = d if greedy else diagnose(ds, model, cands, folds=folds, greedy_mode=True)
            build_report(ds, page_diagnosis, report_dir,
                         title=f"cablelab report: {base['machine']} {start.isoformat()}")
        return rows
    finally:
        if tmp:
            shutil.rmtree(tmp, ignore_errors=True)
