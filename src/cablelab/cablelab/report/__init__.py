"""``cablelab report``: one ``index.html`` with PNG plots of compare, diagnose and identify.

:func:`build_report` draws a greedy :class:`~cablelab.diagnose.result.Diagnosis` (the fits of
its waterfall steps, never refitted here) and writes the answer first, then the evidence:
summary, the answer sentence with the waterfall, the ranking of the candidates (each with the
quantities its significance is decided on), the parameter table with uncertainties, the metrics and the overlay (gaps shaded), residual over time with the worst
segments shaded and after each added effect, residual by regime (a table of the worst regime per
channel, the bar charts folded), residual whiteness and cross-correlation. Every figure has a
caption naming what it shows and its unit. The sections' HTML is built in :mod:`.sections`.
"""
from __future__ import annotations

import html
import os
from dataclasses import dataclass

import numpy as np

from ..dataset import Dataset
from ..diagnose import derived_regimes, worst_segments
from ..diagnose.fit_metrics import fit_metrics
from ..diagnose.result import Diagnosis
from ..errors import CablelabError
from ..fit.threads import blas_single
from . import plots
from .sections import (CSS, _figure, answer_section, metrics_table, parameters_section,
                       ranking_section, regime_section, segments_table, whiteness_section)


@dataclass(frozen=True)
class ReportPage:
    """A written report: ``index`` the page's path, ``figures`` its PNG file names."""

    index: str
    figures: list


@blas_single
def build_report(ds: Dataset, diagnosis: Diagnosis, out_dir, *, title: str = "", warnings=(),
                 overlay: str = "") -> ReportPage:
    """Write ``out_dir/index.html`` + PNGs of a greedy diagnosis of ``ds``
    (:func:`cablelab.workbench.diagnose` with ``greedy_mode``); ``warnings`` (the input checks'
    lines, :func:`cablelab.bagcheck.check_bag`) are shown at the top of the page; ``overlay``:
    path (relative to ``out_dir``) of the model overlay bag the page links (:mod:`cablelab.overlay`).

    Raises:
        CablelabError: the output directory cannot be made.
        ValueError: a diagnosis without its greedy waterfall.
    """
    if not diagnosis.greedy:
        raise ValueError("build_report draws the greedy waterfall: diagnose with greedy_mode=True")
    try:
        os.makedirs(out_dir, exist_ok=True)
    except OSError as exc:
        raise CablelabError(f"{out_dir}: cannot create report directory ({exc.strerror})") from None
    steps = diagnosis.greedy
    folds, alpha, min_gain = diagnosis.folds, diagnosis.alpha, diagnosis.min_gain
    base, fin = steps[0].fit, steps[-1].fit
    regimes = derived_regimes(ds)
    m_base = fit_metrics(ds, base, regimes=regimes, with_whiteness=False)
    m_fin = fit_metrics(ds, fin, regimes=regimes)
    y_meas_b = m_base.y_meas
    # windows where the residual rises most above its own level over the record (normalised by the
    # residual, not the signal: a noisy, well-modelled channel would otherwise take every window)
    segs = worst_segments(ds.t, base.residual, base.residual, ds.channels)
    reg_b, reg_f = m_base.regimes, m_fin.regimes

    figs = []

    def fig(name):
        figs.append(name)
        return os.path.join(out_dir, name)

    plots.waterfall(fig("waterfall.png"), steps)
    plots.overlay(fig("overlay.png"), ds.t, y_meas_b, base.y_hat, fin.y_hat, ds.channels, ds.units,
                  valid=base.valid & fin.valid)
    plots.residual_time(fig("residual_time.png"), ds.t, base.residual, segs, ds.channels, ds.units,
                        "residual of the nominal model; worst segments shaded", valid=base.valid)
    step_figs = []
    for i, st in enumerate(steps[1:], 1):
        name = f"step_{i}_residual.png"
        plots.residual_time(fig(name), ds.t, st.fit.residual, [], ds.channels, ds.units,
                            f"step {i}: + {st.added} (held-out NRMSE {100 * st.error:.2f} %)",
                            valid=st.fit.valid)
        final = " (the final model)" if i == len(steps) - 1 else ""
        step_figs.append((i, name, f"Residual after step {i} (+ {st.added}){final} over time."))
    # whiteness on the decimated residual: a residual of low-passed signals is correlated over
    # fs / (2 f_c) samples by the filter alone
    white = m_fin.whiteness
    for c, (ch, unit) in enumerate(zip(ds.channels, ds.units)):
        plots.residual_regimes(fig(f"regimes_{c}.png"), reg_b, reg_f, ch, unit)
        plots.correlations(fig(f"whiteness_{c}.png"), white[ch], ch)

    parts = [f"<h1>{html.escape(title or 'cablelab report')}</h1>",
             f"<p>plant <b>{ds.plant}</b>, {ds.n} samples at {ds.fs:.4g} Hz from "
             f"{html.escape(ds.source)}; held-out errors by blocked {folds}-fold cross-validation "
             f"(NRMSE: residual RMS / measured RMS).</p>"]
    if warnings:
        parts.append("<div class='warnings'><b>Input warnings</b><ul>"
                     + "".join(f"<li>{html.escape(w)}</li>" for w in warnings) + "</ul></div>")
    if overlay:
        parts.append(f"<p>Measurement, model and residual of every step on one time axis: the overlay bag "
                     f"<a href='{html.escape(overlay)}'>{html.escape(overlay)}</a> (open it in Foxglove or "
                     f"PlotJuggler with the layouts of <code>cablelab layout --plant {ds.plant}</code>)</p>")
    # the answer first: what is missing (waterfall, ranking), then the fitted model, then evidence
    parts.append(answer_section(steps))
    parts.append(ranking_section(steps, alpha=alpha, min_gain=min_gain))
    from ..diagnose.result import ambiguity_lines
    from ..excite import excite_commands

    parts.extend(f"<p class='warnings'>{html.escape(line)}</p>"
                 for line in ambiguity_lines(steps[0].ranking)
                 + excite_commands(steps[0].ranking, diagnosis.plant, ds.source))
    parts.append(parameters_section(fin))
    parts.append("<h2>Measured vs model</h2>")
    parts.append(metrics_table(ds.channels, ds.units, m_base.channels, m_fin.channels))
    n_bad = int(np.sum(~fin.valid))
    gaps = (f" Grey bands: {n_bad} samples ({100 * n_bad / max(ds.n, 1):.1f} %) with no valid "
            "measurement (gaps, NaN, filter edges); nothing is fitted or drawn there." if n_bad else "")
    parts.append(_figure("overlay.png", "Measured output (black) and the output of the nominal "
                         "(orange) and final (blue) models, each channel in its own unit." + gaps))
    parts.append("<h2>Evidence: where the nominal model fails</h2>")
    parts.append(_figure("residual_time.png", "Residual (measured - model) of the nominal model "
                         "over time; the windows where it rises most above its own level (table "
                         "below) shaded gold." + gaps))
    parts.append(segments_table(segs, ds.channels, ds.units))
    if not step_figs:
        parts.append("<p>No effect was added: the nominal model is the final model.</p>")
    for i, name, caption in step_figs:
        parts.append(_figure(name, caption))
    parts.append(regime_section(reg_b, reg_f, ds.channels, ds.units, y_meas_b))
    parts.append(whiteness_section(white, ds.channels))
    doc = (f"<!DOCTYPE html><html><head><meta charset='utf-8'><title>cablelab report</title>"
           f"<style>{CSS}</style></head><body>{''.join(parts)}</body></html>")
    index = os.path.join(out_dir, "index.html")
    with open(index, "w", encoding="utf-8") as fh:
        fh.write(doc)
    return ReportPage(index, figs)
