"""The fleet report ``OUT/index.html``: drift findings, per-parameter value with its confidence
band over time per machine, a machine x effect heat map of significant effects, failures, and a
table of bags linking to each bag's own ``cablelab report`` page.
"""
from __future__ import annotations

import datetime as _dt
import html
import os
import re
from pathlib import Path

import numpy as np

from ..report.sections import CSS, _table
from ..report.plots import DPI

Z95 = 1.959963984540054  # two-sided 95 % normal quantile: band = value +- Z95 stderr


def _slug(text: str) -> str:
    return re.sub(r"[^A-Za-z0-9_.-]+", "_", text)


def heatmap(path, rows: list[dict]):
    """machines x effects: fraction of a machine's bags in which the effect is significant
    (candidates) -- nominal effects are marked 'model'."""
    import matplotlib.pyplot as plt

    ok = [r for r in rows if r["status"] == "ok" and r["effect"]]
    machines = sorted({r["machine"] for r in ok})
    effects = sorted({r["effect"] for r in ok})
    frac = np.full((len(machines), len(effects)), np.nan)
    model = np.zeros_like(frac, dtype=bool)
    for i, m in enumerate(machines):
        for j, e in enumerate(effects):
            rs = [r for r in ok if r["machine"] == m and r["effect"] == e]
            sig = [bool(r["significant"]) or (r["in_model"] and r["rank"] is not None) for r in rs
                   if r["significant"] is not None]
            if sig:
                frac[i, j] = np.mean(sig)
            model[i, j] = any(r["in_model"] and r["rank"] is None for r in rs)
    fig, ax = plt.subplots(figsize=(1.6 + 1.1 * len(effects), 1.2 + 0.35 * len(machines)))
    im = ax.imshow(np.where(model, np.nan, frac), vmin=0, vmax=1, cmap="Reds", aspect="auto")
    for i in range(len(machines)):
        for j in range(len(effects)):
            txt = "model" if model[i, j] else ("-" if np.isnan(frac[i, j]) else f"{frac[i, j]:.0%}")
            dark = not model[i, j] and np.nan_to_num(frac[i, j]) > 0.6
            ax.text(j, i, txt, ha="center", va="center", fontsize=7, color="white" if dark else "black")
    ax.set_xticks(range(len(effects)), effects, rotation=30, ha="right", fontsize=8)
    ax.set_yticks(range(len(machines)), machines, fontsize=8)
    ax.set_title("share of bags in which the effect is significant")
    fig.colorbar(im, ax=ax, fraction=0.03)
    fig.tight_layout()
    fig.savefig(path, dpi=DPI)
    plt.close(fig)


def series_plot(path, series_list, tests_by_key: dict):
    """One parameter, every machine: value with its 95 % band over time; drifting machines drawn
    bold with the change marked."""
    import matplotlib.pyplot as plt

    fig, ax = plt.subplots(figsize=(9, 3.6))
    for s in series_list:
        test = tests_by_key.get((s.machine, s.effect, s.param))
        drift = bool(test and test["drift"])
        t = [x.replace(tzinfo=None) for x in s.time]
        band = Z95 * np.nan_to_num(s.stderr, nan=0.0)
        line, = ax.plot(t, s.value, "o-" if drift else ".-", lw=2.2 if drift else 0.8, ms=4,
                        label=s.machine + (" (drift)" if drift else ""))
        ax.fill_between(t, s.value - band, s.value + band, color=line.get_color(), alpha=0.18)
        if drift:
            cp = test["change"]
            ax.plot(t, cp.fit, "--", color=line.get_color(), lw=1)
            ax.axvline(t[cp.k], color=line.get_color(), ls=":", lw=1.5)
    s0 = series_list[0]
    ax.set_title(f"{s0.effect}: {s0.param} (band: 95 % from the identification standard error)")
    ax.set_ylabel(s0.param)
    ax.legend(fontsize=7, ncol=2)
    fig.autofmt_xdate()
    fig.tight_layout()
    fig.savefig(path, dpi=DPI)
    plt.close(fig)


def write_report(out, rows: list[dict], findings, tests, *, title: str = "cablelab fleet report",
                 root: str = "") -> str:
    """Write ``out/index.html`` (+ PNGs under ``out/fig/``); returns the index path."""
    out = Path(out)
    figdir = out / "fig"
    figdir.mkdir(parents=True, exist_ok=True)
    parts = [f"<!doctype html><html><head><meta charset='utf-8'><title>{html.escape(title)}</title>"
             f"<style>{CSS}</style></head><body><h1>{html.escape(title)}</h1>"]
    bags = {}
    for r in rows:
        bags.setdefault(r["bag_hash"] + r["bag"], r)
    failed = [r for r in bags.values() if r["status"] != "ok"]
    machines = sorted({r["machine"] for r in bags.values() if r["machine"]})
    parts.append(f"<p>{len(bags)} bags under <code>{html.escape(root)}</code>, {len(machines)} machines, "
                 f"{len(failed)} failed. Results: <a href='results.parquet'>results.parquet</a>.</p>")
    parts.append("<h2>Drift findings</h2>")
    if findings:
        parts.append(_table([[html.escape(f.machine), html.escape(f.effect), html.escape(f.param),
                              f.since.isoformat(), f.kind, f"{f.before:.5g}", f"{f.after:.5g}",
                              f"{f.p_value:.2g}", html.escape(f.bag)] for f in findings],
                            ["machine", "effect", "parameter", "since (first changed bag)", "kind",
                             "mean before", "last value", "p (Holm)", "bag"]))
    else:
        parts.append(f"<p>No parameter drifts (of {len(tests)} series tested).</p>")
    parts.append("<h2>Which effects are significant, per machine</h2>")
    if any(r["status"] == "ok" for r in rows):
        heatmap(figdir / "heatmap.png", rows)
        parts.append("<img src='fig/heatmap.png' alt='machine x effect heat map'>")
    parts.append("<h2>Parameters over time</h2>")
    by_param: dict[tuple, list] = {}
    for t in tests:
        s = t["series"]
        by_param.setdefault((s.effect, s.param), []).append(s)
    keyed = {(t["series"].machine, t["series"].effect, t["series"].param): t for t in tests}
    for (eff, par), sl in sorted(by_param.items()):
        name = f"param_{_slug(eff)}_{_slug(par)}.png"
        series_plot(figdir / name, sl, keyed)
        parts.append(f"<h3>{html.escape(eff)}: {html.escape(par)}</h3><img src='fig/{name}' alt='{html.escape(par)}'>")
    if failed:
        parts.append("<h2>Failed bags</h2>")
        parts.append(_table([[html.escape(r["bag"]), html.escape(r["status"])] for r in failed],
                            ["bag", "reason"]))
    parts.append("<h2>Bags</h2>")
    trs = []
    for r in sorted(bags.values(), key=lambda r: (r["machine"], str(r["start_time"]), r["bag"])):
        rep = out / "bags" / r["bag_hash"] / "index.html"
        link = (f"<a href='bags/{r['bag_hash']}/index.html'>report</a>" if rep.exists() else
                f"<code>cablelab report {html.escape(r['url'])} -o DIR</code>")
        trs.append([html.escape(r["machine"]), html.escape(str(r["start_time"] or "")), html.escape(r["bag"]),
                    html.escape(("ok; " + r["warnings"] if r.get("warnings") else "ok")
                                if r["status"] == "ok" else "failed"), link])
    parts.append(_table(trs, ["machine", "start", "bag", "status", "per-bag report"]))
    parts.append("</body></html>")
    index = out / "index.html"
    tmp = out / f".index.html.{os.getpid()}.tmp"
    tmp.write_text("\n".join(parts), encoding="utf-8")
    os.replace(tmp, index)
    return str(index)


def summary(rows: list[dict], findings) -> dict:
    """The ``--json`` object of CONTRACT section 5, plus ``held`` when some bags do not excite
    every parameter: their number (those parameters held with a warning)."""
    bags, held = {}, set()
    for r in rows:
        bags.setdefault((r["bag"]), r["status"])
        if r.get("warnings") and r["status"] == "ok":
            held.add(r["bag"])
    out = {"bags": len(bags), "failed": sum(1 for s in bags.values() if s != "ok"),
           "drift": [{"machine": f.machine, "effect": f.effect, "param": f.param,
                      "since": f.since.astimezone(_dt.timezone.utc).isoformat().replace("+00:00", "Z")} for f in findings]}
    if held:
        out["held"] = len(held)
    return out

