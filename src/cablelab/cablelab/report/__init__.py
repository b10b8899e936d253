"""``cablelab report``: one ``index.html`` with PNG plots of compare, diagnose and identify.

:func:`build_report` runs the analysis once (nominal fit, greedy diagnosis, final fit) and writes
the sections: summary, waterfall, candidate ranking with explanations, parameter table with
uncertainties, overlay, residual over time with the worst segments shaded, residual by regime,
residual whiteness and cross-correlation.
"""
from __future__ import annotations

import html
import os
import time

import numpy as np

from ..diagnose import derived_regimes, greedy, residual_by_regime, whiteness, worst_segments
from ..diagnose.metrics import channel_metrics
from ..errors import CablelabError
from ..fit import identify
from ..fit.threads import blas_single
from ..model import Dataset, Model
from ..workbench import _decimation
from . import plots


def _table(rows: list[list], header: list[str]) -> str:
    head = "".join(f"<th>{html.escape(h)}</th>" for h in header)
    body = "".join("<tr>" + "".join(f"<td>{c}</td>" for c in r) + "</tr>" for r in rows)
    return f"<table><thead><tr>{head}</tr></thead><tbody>{body}</tbody></table>"


def _num(v, fmt="{:.5g}") -> str:
    return "-" if v is None else fmt.format(v)


CSS = ("body{font-family:sans-serif;max-width:1100px;margin:auto;padding:1em}"
       "table{border-collapse:collapse;margin:0.5em 0}td,th{border:1px solid #ccc;padding:3px 8px;"
       "font-size:90%;text-align:left}th{background:#eee}img{max-width:100%}.sig{color:#060;font-weight:bold}"
       ".warnings{background:#fff4e0;border:1px solid #e0a040;padding:0.3em 1em}")


@blas_single
def build_report(ds: Dataset, model: Model, candidates, out_dir, *, folds: int = 5,
                 title: str = "", quiet: bool = True, warnings=()) -> dict:
    """Analyse and write ``out_dir/index.html`` + PNGs; ``warnings`` (the input checks' lines,
    :func:`cablelab.bagcheck.check_bag`) are shown at the top of the page.

    Returns:
        ``{"index": path, "figures": [...], "steps": greedy steps, "seconds": elapsed}``.
    """
    t0 = time.monotonic()
    try:
        os.makedirs(out_dir, exist_ok=True)
    except OSError as exc:
        raise CablelabError(f"{out_dir}: cannot create report directory ({exc.strerror})") from None
    steps = greedy(model, ds, candidates, folds=folds, quiet=quiet)
    final_model = model.with_effects(steps[-1]["effects"])
    base = identify(model, ds)
    fin = identify(final_model, ds)
    y_meas = np.where(fin.valid[:, None], fin.residual + fin.y_hat, np.nan)
    y_meas_b = np.where(base.valid[:, None], base.residual + base.y_hat, np.nan)
    segs = worst_segments(ds.t, base.residual, y_meas_b, ds.channels)
    regimes = derived_regimes(ds)
    reg_b = residual_by_regime(base.residual, y_meas_b, regimes, ds.channels)
    reg_f = residual_by_regime(fin.residual, y_meas, regimes, ds.channels)
    met_b = channel_metrics(y_meas_b, base.y_hat, base.valid)
    met_f = channel_metrics(y_meas, fin.y_hat, fin.valid)

    figs = []

    def fig(name):
        figs.append(name)
        return os.path.join(out_dir, name)

    plots.waterfall(fig("waterfall.png"), steps)
    plots.overlay(fig("overlay.png"), ds.t, y_meas_b, base.y_hat, fin.y_hat, ds.channels, ds.units)
    plots.residual_time(fig("residual_time.png"), ds.t, base.residual, segs, ds.channels, ds.units,
                        "residual of the nominal model; worst segments shaded")
    plots.residual_time(fig("residual_time_final.png"), ds.t, fin.residual, [], ds.channels,
                        ds.units, "residual of the final model")
    white = {}
    for c, ch in enumerate(ds.channels):
        plots.residual_regimes(fig(f"regimes_{c}.png"), reg_b, reg_f, ch)
        white[ch] = whiteness(fin.residual[:, c], ds.inputs, decimate=_decimation(ds))  # issue 10
        plots.correlations(fig(f"whiteness_{c}.png"), white[ch], ch)

    parts = [f"<h1>{html.escape(title or 'cablelab report')}</h1>",
             f"<p>plant <b>{ds.plant}</b>, {ds.n} samples at {ds.fs:.4g} Hz from "
             f"{html.escape(ds.source)}; held-out errors by blocked {folds}-fold cross-validation.</p>"]
    if warnings:
        parts.append("<div class='warnings'><b>Input warnings</b><ul>"
                     + "".join(f"<li>{html.escape(w)}</li>" for w in warnings) + "</ul></div>")
    parts.append("<h2>Adding the missing effects</h2><img src='waterfall.png'>")
    rows = [[i, html.escape(s["added"] or "nominal: " + " + ".join(s["effects"])),
             _num(100 * s["error"], "{:.2f} %"),
             html.escape(", ".join(f"{k} = {v:.5g} +- {s['stderr'].get(k, 0):.2g} {s['units'].get(k, '')}"
                                   for k, v in s["params"].items()))] for i, s in enumerate(steps)]
    parts.append(_table(rows, ["step", "model", "held-out NRMSE", "parameters (full record)"]))
    for i, st in enumerate(steps):
        if i == 0:
            continue  # the nominal residual is plotted below
        ident_i = fin if i == len(steps) - 1 else identify(model.with_effects(st["effects"]), ds)
        name = f"step_{i}_residual.png"
        plots.residual_time(fig(name), ds.t, ident_i.residual, [], ds.channels, ds.units,
                            f"step {i}: + {st['added']} (held-out NRMSE {100 * st['error']:.2f} %)")
        parts.append(f"<img src='{name}'>")
    parts.append("<h2>Which effect is missing (nominal model)</h2>")
    rows = [[f"<span class='sig'>{r['effect']}</span>" if r["significant"] else r["effect"],
             _num(None if r["error_after"] is None else 100 * r["error_after"], "{:.2f} %"),
             "yes" if r["significant"] else "no", _num(r.get("p_value"), "{:.2g}"),
             html.escape(r["explanation"])] for r in steps[0]["ranking"]]
    parts.append(_table(rows, ["effect", "held-out NRMSE with it", "significant", "p", "explanation"]))
    from ..diagnose.result import ambiguity_lines

    from ..diagnose.result import excite_commands

    parts.extend(f"<p class='warnings'>{html.escape(line)}</p>"
                 for line in ambiguity_lines(steps[0]["ranking"])
                 + excite_commands(steps[0]["ranking"], model.plant, ds.source))
    parts.append("<h2>Parameters of the final model</h2>")
    rows = [[html.escape(r["name"]), _num(r["value"], "{:.6g}"), _num(r["stderr"], "{:.2g}"),
             html.escape(r["unit"]), "fixed" if r["fixed"] else ""] for r in fin.table()]
    parts.append(_table(rows, ["parameter", "value", "std. error", "unit", ""]))
    parts.append(f"<p>rank {fin.linear.rank}, condition number {fin.linear.cond:.3g}"
                 + (f"; unidentifiable: {html.escape('; '.join(fin.linear.unidentifiable))}"
                    if fin.linear.unidentifiable else "") + "</p>")
    parts.append("<h2>Measured vs model</h2>")
    rows = [[html.escape(f"{ch} [{unit}]"), _num(100 * mb["nrmse"], "{:.2f} %"),
             _num(100 * mf["nrmse"], "{:.2f} %"), _num(mf["fit_percent"], "{:.1f} %"),
             _num(mf["pearson"], "{:.4f}"), _num(mf["mae"]), _num(mf["mre"], "{:.3g}"),
             _num(mf["max_abs"])]
            for ch, unit, mb, mf in zip(ds.channels, ds.units, met_b, met_f)]
    parts.append(_table(rows, ["channel [unit]", "NRMSE nominal", "NRMSE final", "fit", "Pearson",
                               "MAE final [unit]", "MRE", "max abs final [unit]"]))
    parts.append("<img src='overlay.png'>")
    parts.append("<h2>Where the nominal model fails</h2><img src='residual_time.png'>")
    rows = [[s["channel"], f"{s['t_start']:.3f}", f"{s['t_end']:.3f}", f"{100 * s['error']:.1f} %"]
            for s in segs]
    parts.append(_table(rows, ["channel", "from [s]", "to [s]", "window NRMSE"]))
    parts.append("<img src='residual_time_final.png'>")
    parts.append("<h2>Residual by operating regime</h2>")
    for c, _ in enumerate(ds.channels):
        parts.append(f"<img src='regimes_{c}.png'>")
    parts.append("<h2>Residual whiteness of the final model</h2>")
    for c, ch in enumerate(ds.channels):
        w = white[ch]
        parts.append(f"<p>{ch}: {100 * w['outside']:.0f} % of autocorrelation lags outside the 99 % "
                     f"band ({'white' if w['white'] else 'not white'}).</p><img src='whiteness_{c}.png'>")
    doc = (f"<!DOCTYPE html><html><head><meta charset='utf-8'><title>cablelab report</title>"
           f"<style>{CSS}</style></head><body>{''.join(parts)}</body></html>")
    index = os.path.join(out_dir, "index.html")
    with open(index, "w", encoding="utf-8") as fh:
        fh.write(doc)
    return {"index": index, "figures": figs, "steps": steps, "seconds": time.monotonic() - t0}
