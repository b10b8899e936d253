"""The report's HTML sections, one function each, plain strings assembled by
:func:`cablelab.report.build_report`: the answer (sentence, waterfall, steps), the ranking of the
candidates with the quantities each significance decision is made on, the parameters, the metrics
table, the worst segments, the residual-by-regime summary, the residual whiteness; and the small helpers they share (tables, numbers, captioned figures).
"""
from __future__ import annotations

import html

import numpy as np

from ..diagnose.ranking import ALPHA, MIN_GAIN
from ..diagnose.result import Candidate, Step


def _table(rows: list[list], header: list[str]) -> str:
    head = "".join(f"<th>{html.escape(h)}</th>" for h in header)
    body = "".join("<tr>" + "".join(f"<td>{c}</td>" for c in r) + "</tr>" for r in rows)
    return f"<table><thead><tr>{head}</tr></thead><tbody>{body}</tbody></table>"


def _num(v, fmt="{:.5g}") -> str:
    return "-" if v is None else fmt.format(v)


CSS = ("body{font-family:sans-serif;max-width:1100px;margin:auto;padding:1em}"
       "table{border-collapse:collapse;margin:0.5em 0}td,th{border:1px solid #ccc;padding:3px 8px;"
       "font-size:90%;text-align:left}th{background:#eee}img{max-width:100%}.sig{color:#060;font-weight:bold}"
       ".warnings{background:#fff4e0;border:1px solid #e0a040;padding:0.3em 1em}"
       "figure{margin:0.8em 0}figcaption{font-size:90%;color:#333;margin-top:0.2em}"
       ".answer{font-size:115%;background:#eef6ee;border-left:4px solid #060;padding:0.4em 0.8em}")


def _figure(src: str, caption: str) -> str:
    """One figure with its caption (every plot of the report says what it shows, in which unit)."""
    return (f"<figure><img src='{html.escape(src)}' alt='{html.escape(caption)}'>"
            f"<figcaption>{html.escape(caption)}</figcaption></figure>")


def _channel_rms(y: np.ndarray) -> float | None:
    y = y[np.isfinite(y)]
    return float(np.sqrt(np.mean(y ** 2))) if y.size else None


def _model_name(step: Step) -> str:
    return " + ".join(step.effects) or "no effects"


def answer_section(steps: list[Step]) -> str:
    """The answer in one sentence, the waterfall and its table of steps."""
    first, last = steps[0], steps[-1]
    added = [s.added for s in steps[1:]]
    if added:
        names = ", ".join(f"<b>{html.escape(a)}</b>" for a in added)
        answer = (f"The nominal model ({html.escape(_model_name(first))}) misses {names}: adding "
                  f"{'it' if len(added) == 1 else 'them, one at a time,'} lowers the held-out NRMSE "
                  f"from {100 * first.error:.2f} % to {100 * last.error:.2f} %."
                  + ("" if any(r.significant for r in last.ranking)
                     else " No further candidate is significant."))
    else:
        answer = (f"No candidate effect is significant: the nominal model ({html.escape(_model_name(first))}, "
                  f"held-out NRMSE {100 * first.error:.2f} %) is not improved on held-out data by "
                  "any of them.")
    rows = [[i, html.escape(s.added or "nominal: " + _model_name(s)),
             _num(100 * s.error, "{:.2f} %"),
             html.escape(", ".join(f"{k} = {v:.5g} +- {s.stderr.get(k, 0):.2g} {s.units.get(k, '')}"
                                   for k, v in s.params.items()))] for i, s in enumerate(steps)]
    return ("<h2>Answer: which effect is missing</h2>"
            f"<p class='answer'>{answer}</p>"
            + _figure("waterfall.png", "Held-out NRMSE of the nominal model and after adding each "
                      "significant effect in turn (greedy).")
            + _table(rows, ["step", "model", "held-out NRMSE", "parameters (full record)"]))


def decision(row: Candidate, threshold: float, min_gain: float) -> tuple[bool, str]:
    """Why a ranked candidate is, or is not, significant, from the criteria of
    :mod:`cablelab.diagnose.ranking` (held-out gain, held-out error falls, likelihood-ratio p,
    identifiable): ``(significant, reason)``; the reason names the first criterion that fails."""
    if row.error_after is None:
        return False, "cannot be fitted"
    gain, p = row.gain, row.p_value
    if gain is None or gain < min_gain:
        return False, f"held-out gain below {100 * min_gain:g} %"
    if not row.error_after < row.error_before:
        return False, "held-out error over all channels does not fall"
    if p is None or not p < threshold:
        return False, f"p not below {threshold:.2g}"
    if not (row.identifiability or {}).get("identifiable", True):
        return False, "not identifiable in this recording"
    return True, "all criteria met"


def _p(v) -> str:
    if v is None:
        return "-"
    return "< 1e-300" if v < 1e-300 else f"{v:.2g}"


def _ranking_table(ranking: list[Candidate], alpha: float, min_gain: float) -> str:
    """One ranking: every candidate with the quantities its significance is decided on, the
    decision and its reason; the p threshold (Bonferroni over this ranking's candidates) heads the
    p column."""
    threshold = alpha / max(len(ranking), 1)
    rows = []
    for r in ranking:
        sig, reason = decision(r, threshold, min_gain)
        if sig != bool(r.significant):   # the diagnosis decided on more than these criteria
            sig, reason = bool(r.significant), "see the explanation"
        ident = r.identifiability
        rows.append([f"<span class='sig'>{html.escape(r.effect)}</span>" if sig else html.escape(r.effect),
                     _num(None if r.error_after is None else 100 * r.error_after, "{:.2f} %"),
                     _num(None if r.gain is None else 100 * r.gain, "{:.1f} %"),
                     _p(r.p_value),
                     "-" if ident is None else ("yes" if ident.get("identifiable", True) else "no"),
                     ("yes" if sig else "no") + f" ({html.escape(reason)})",
                     html.escape(r.explanation)])
    head = ["effect", "held-out NRMSE with it", f"held-out gain (significant from {100 * min_gain:g} %)",
            f"p, LR test on the full record (significant below {threshold:.2g})",
            "identifiable", "significant", "explanation"]
    return _table(rows, head)


def ranking_section(steps: list[Step], *, alpha: float = ALPHA, min_gain: float = MIN_GAIN) -> str:
    """Which effect is missing: the candidates ranked by held-out error when added to the nominal
    model (shown), then to the model of each greedy step (folded), each with the quantities its
    significance is decided on next to the decision and its reason."""
    out = [f"<h2>Ranking of the candidate effects (nominal model, held-out NRMSE "
           f"{100 * steps[0].error:.2f} %)</h2>"
           f"<p>A candidate is significant when all of these hold: its <b>held-out gain</b> (the "
           f"relative drop of the held-out error on the channels it changes) is at least "
           f"{100 * min_gain:g} %; the held-out NRMSE over all channels falls; the likelihood-ratio "
           f"test on the full record rejects \"no gain\" at p &lt; {alpha:g} / m (m = candidates "
           f"in the ranking, Bonferroni; effective sample count); and its parameters are "
           f"identifiable in this recording. A tiny p alone does not make an effect significant: "
           f"with thousands of samples almost any extra parameter lowers the in-sample error. An "
           f"effect added at a later step is ranked against the model holding the earlier ones "
           f"(rankings after each step below).</p>",
           _ranking_table(steps[0].ranking, alpha, min_gain)]
    for i, st in enumerate(steps[1:], 1):
        last = (" (no remaining candidate is significant)"
                if i == len(steps) - 1 and not any(r.significant for r in st.ranking) else "")
        out.append(f"<details><summary>Ranking after step {i} (+ {html.escape(st.added)}, held-out "
                   f"NRMSE {100 * st.error:.2f} %){last}</summary>"
                   + _ranking_table(st.ranking, alpha, min_gain) + "</details>")
    return "".join(out)


def metrics_table(channels, units, met_b, met_f) -> str:
    """Error metrics per channel; a dimensional column carries the channels' unit in its header
    when they share one, otherwise in each cell."""
    shared = units[0] if len(set(units)) == 1 else None

    def dim(v, unit):
        return _num(v) if shared is not None or v is None else f"{_num(v)} {html.escape(unit)}"

    def head(name):
        return f"{name} [{shared}]" if shared is not None else name

    def pct(v):       # no NRMSE on a channel without signal (an unactuated joint's zero force)
        return _num(None if v is None else 100 * v, "{:.2f} %")

    rows = [[html.escape(f"{ch} [{unit}]"), pct(mb["nrmse"]), pct(mf["nrmse"]),
             _num(mf["fit_percent"], "{:.1f} %"),
             _num(mf["pearson"], "{:.4f}"), dim(mf["mae"], unit), _num(mf["mre"], "{:.3g}"),
             dim(mf["max_abs"], unit)]
            for ch, unit, mb, mf in zip(channels, units, met_b, met_f)]
    return _table(rows, ["channel [unit]", "NRMSE nominal", "NRMSE final", "fit", "Pearson",
                         head("MAE final"), "MRE", head("max abs final")])


def regime_section(reg_b: list[dict], reg_f: list[dict], channels, units, y_meas: np.ndarray,
                   min_share: float = 0.02) -> str:
    """Residual by operating regime: per channel the regime where the nominal model's residual is
    largest (holding at least ``min_share`` of the samples) and the final model's there; the
    per-channel bar charts below it, folded."""
    final = {(r["regime"], r["label"], r["channel"]): r for r in reg_f}
    rows = []
    for ch, unit in zip(channels, units):
        mine = [r for r in reg_b if r["channel"] == ch and r["nrmse"] is not None]
        n_max = max((r["n"] for r in mine), default=0)
        mine = [r for r in mine if r["n"] >= min_share * n_max]
        if not mine:
            continue
        w = max(mine, key=lambda r: r["nrmse"])
        f = final.get((w["regime"], w["label"], ch), {})
        rows.append([html.escape(ch), html.escape(f"{w['regime']}: {w['label']}"), w["n"],
                     f"{w['rms']:.4g} {html.escape(unit)}", _num(100 * w["nrmse"], "{:.1f} %"),
                     _num(None if f.get("nrmse") is None else 100 * f["nrmse"], "{:.1f} %")])
    out = ["<h2>Residual by operating regime</h2><p>The residual RMS within one operating regime "
           "(samples sharing a velocity sign, closeness to a velocity reversal, acceleration level, "
           "or the plant's own regimes) as a percentage of the channel's RMS over the whole record. "
           "A regime where the nominal model's residual stands out is where the missing effect "
           "lives. Per channel, the regime where it is largest:</p>",
           _table(rows, ["channel", "regime", "samples", "nominal residual RMS",
                         "in % of the channel RMS, nominal", "final"])]
    for c, (ch, unit) in enumerate(zip(channels, units)):
        rms = _channel_rms(y_meas[:, c])
        out.append(f"<details><summary>{html.escape(ch)}: every regime</summary>"
                   + _figure(f"regimes_{c}.png", f"Residual of {ch} by regime, in % of the RMS of "
                             f"{ch} over the record ({_num(rms, '{:.4g}')} {unit}), nominal model "
                             "(orange) vs final model (blue); n = samples in the regime.")
                   + "</details>")
    return "".join(out)


def parameters_section(fit) -> str:
    """The final model's parameters with standard errors and units (a source column when some
    were fixed with ``--fix``), and the rank and condition of its regressor."""
    table = fit.table()
    any_fixed = any(r["fixed"] for r in table)     # a column for --fix only when it was used
    rows = [[html.escape(r["name"]), _num(r["value"], "{:.6g}"), _num(r["stderr"], "{:.2g}"),
             html.escape(r["unit"])] + (["fixed (--fix)" if r["fixed"] else "fitted"] if any_fixed else [])
            for r in table]
    return ("<h2>Parameters of the final model</h2>"
            + _table(rows, ["parameter", "value", "std. error", "unit"] + (["source"] if any_fixed else []))
            + f"<p>rank {fit.linear.rank}, condition number {fit.linear.cond:.3g}"
            + (f"; unidentifiable: {html.escape('; '.join(fit.linear.unidentifiable))}"
               if fit.linear.unidentifiable else "") + "</p>")


def segments_table(segs: list[dict], channels, units) -> str:
    """The worst windows of the residual (:func:`~cablelab.diagnose.localise.worst_segments`)."""
    unit_of = dict(zip(channels, units))
    rows = [[html.escape(s["channel"]), f"{s['t_start']:.3f}", f"{s['t_end']:.3f}",
             f"{s['rms']:.4g} {html.escape(unit_of[s['channel']])}", f"{s['error']:.2f}"] for s in segs]
    return _table(rows, ["channel", "from [s]", "to [s]", "residual RMS in the window",
                         "x the channel's residual RMS over the record"])


def whiteness_section(white: dict, channels) -> str:
    """Whiteness of the final model's residual per channel: the table and the figures
    ``whiteness_<c>.png``."""
    out = ["<h2>Residual whiteness of the final model</h2><p>A model that explains "
           "everything leaves a white residual: autocorrelation inside the 99 % band at every "
           "lag and no correlation with the inputs.</p>"]
    rows = [[html.escape(ch), f"{100 * white[ch]['outside']:.0f} %", "yes" if white[ch]["white"] else "no",
             html.escape(", ".join(k for k, x in white[ch]["cross"].items() if not x["uncorrelated"]) or "none")]
            for ch in channels]
    out.append(_table(rows, ["channel", "autocorrelation lags outside the 99 % band", "white",
                             "inputs the residual still correlates with"]))
    for c, ch in enumerate(channels):
        w = white[ch]
        out.append(_figure(f"whiteness_{c}.png", f"{ch}: {100 * w['outside']:.0f} % of "
                           f"autocorrelation lags outside the 99 % band "
                           f"({'white' if w['white'] else 'not white'}); lags in samples."))
    return "".join(out)
