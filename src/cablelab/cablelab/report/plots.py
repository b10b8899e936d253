"""The report's figures (matplotlib, Agg backend), one function per plot, each writing a PNG.

Long records are thinned for drawing only (at most ``MAX_POINTS`` per line); numbers in the
report always come from the full data.
"""
from __future__ import annotations

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402

MAX_POINTS = 4000
DPI = 90


def _save(fig, path) -> None:
    fig.tight_layout()
    fig.savefig(path, dpi=DPI)
    plt.close(fig)


def _robust_ylim(ax, *series) -> None:
    """Zoom the y axis onto the bulk of the data when a few isolated spikes (e.g. one impact or a
    lock-step hiccup) would otherwise flatten everything; says how many samples are off-scale."""
    y = np.concatenate([np.asarray(v, dtype=float).ravel() for v in series])
    y = y[np.isfinite(y)]
    if y.size < 100:
        return
    lo, hi = np.percentile(y, [0.1, 99.9])
    span = hi - lo
    if span <= 0 or (y.max() - y.min()) < 1.6 * span:
        return
    lo, hi = lo - 0.15 * span, hi + 0.15 * span
    ax.set_ylim(lo, hi)
    n = int(np.sum((y < lo) | (y > hi)))
    if n:
        ax.text(0.01, 0.97, f"{n} samples off-scale", transform=ax.transAxes, fontsize=7,
                va="top", color="gray")


def invalid_spans(t: np.ndarray, valid: np.ndarray) -> list[tuple[float, float]]:
    """``[(t_start, t_end)]`` of every run of invalid samples, each widened by half a sample
    period on both sides so a single invalid sample still shows."""
    bad = ~np.asarray(valid, dtype=bool)
    if not bad.any():
        return []
    edges = np.diff(np.concatenate(([0], bad.astype(np.int8), [0])))
    starts, ends = np.flatnonzero(edges == 1), np.flatnonzero(edges == -1) - 1
    half = 0.5 * float(np.median(np.diff(t))) if t.size > 1 else 0.0
    return [(float(t[a]) - half, float(t[b]) + half) for a, b in zip(starts, ends)]


def _thin_masked(t, y, valid):
    """``t, y`` thinned for drawing, NaN wherever a thinning window holds an invalid sample, so a
    line breaks at every gap however short."""
    step = max(1, t.size // MAX_POINTS)
    y = np.where(np.asarray(valid, dtype=bool)[:, None] if y.ndim == 2 else valid, y, np.nan)
    if step == 1:
        return t, y
    idx = np.arange(0, t.size, step)
    bad = np.minimum.reduceat(np.asarray(valid, dtype=np.int8), idx) == 0
    out = y[idx].copy()
    out[bad] = np.nan
    return t[idx], out


def _shade_gaps(ax, spans, label: bool) -> None:
    for k, (a, b) in enumerate(spans):
        ax.axvspan(a, b, color="0.6", alpha=0.35, lw=0,
                   label="no valid measurement (not fitted)" if label and k == 0 else None)


def overlay(path, t, y_meas, y_base, y_final, channels, units, labels=("nominal", "final"),
            valid=None) -> None:
    """Measured vs model output per channel (nominal and final model); lines break where
    ``valid`` is False and those spans are shaded grey (with a legend entry)."""
    c = len(channels)
    valid = np.isfinite(y_meas).all(axis=1) if valid is None else np.asarray(valid, dtype=bool)
    spans = invalid_spans(t, valid)
    fig, axes = plt.subplots(c, 1, figsize=(10, 2.6 * c + 0.4), squeeze=False, sharex=True)
    tt, ym = _thin_masked(t, y_meas, valid)
    _, yb = _thin_masked(t, y_base, valid)
    _, yf = _thin_masked(t, y_final, valid)
    for i, ax in enumerate(axes[:, 0]):
        _shade_gaps(ax, spans, label=i == 0)
        ax.plot(tt, ym[:, i], color="k", lw=0.8, label="measured")
        ax.plot(tt, yb[:, i], color="tab:orange", lw=0.8, alpha=0.8, label=labels[0])
        ax.plot(tt, yf[:, i], color="tab:blue", lw=0.8, alpha=0.8, label=labels[1])
        ax.set_ylabel(f"{channels[i]} [{units[i]}]")
        _robust_ylim(ax, *(np.where(valid, y[:, i], np.nan) for y in (y_meas, y_base, y_final)))
    # one legend above the first panel, out of the data's way
    axes[0, 0].legend(loc="lower right", bbox_to_anchor=(1.0, 1.0), ncol=4, fontsize=8, frameon=False)
    axes[0, 0].set_title("measured vs model output", loc="left", fontsize=10)
    axes[-1, 0].set_xlabel("time [s]")
    _save(fig, path)


def residual_time(path, t, residual, segments, channels, units, title="", valid=None) -> None:
    """Residual over time with the worst segments shaded gold and invalid samples grey."""
    c = len(channels)
    valid = np.isfinite(residual).all(axis=1) if valid is None else np.asarray(valid, dtype=bool)
    spans = invalid_spans(t, valid)
    fig, axes = plt.subplots(c, 1, figsize=(10, 2.4 * c), squeeze=False, sharex=True)
    tt, rr = _thin_masked(t, residual, valid)
    for i, ax in enumerate(axes[:, 0]):
        _shade_gaps(ax, spans, label=i == 0)
        ax.plot(tt, rr[:, i], color="tab:red", lw=0.7)
        ax.axhline(0, color="k", lw=0.5)
        _robust_ylim(ax, np.where(valid, residual[:, i], np.nan))
        for seg in segments:
            if seg["channel"] == channels[i]:
                ax.axvspan(seg["t_start"], seg["t_end"], color="gold", alpha=0.35)
        ax.set_ylabel(f"residual {channels[i]} [{units[i]}]")
    if spans:
        axes[0, 0].legend(loc="lower right", bbox_to_anchor=(1.0, 1.0), fontsize=8, frameon=False)
    axes[0, 0].set_title(title, loc="left", fontsize=10)
    axes[-1, 0].set_xlabel("time [s]")
    _save(fig, path)


def residual_regimes(path, rows_base, rows_final, channel, unit: str = "") -> None:
    """Residual NRMSE per regime label, nominal vs final model (one channel), with each regime's
    sample count and the residual RMS in the channel's unit."""
    base = [r for r in rows_base if r["channel"] == channel]
    final = {(r["regime"], r["label"]): r for r in rows_final if r["channel"] == channel}
    names = [f"{r['regime']}: {r['label']} (n = {r['n']})" for r in base]
    vb = [100 * (r["nrmse"] or 0) for r in base]
    vf = [100 * (final.get((r["regime"], r["label"]), {}).get("nrmse") or 0) for r in base]
    fig, ax = plt.subplots(figsize=(10, 0.32 * len(names) + 1.5))
    yy = np.arange(len(names))
    ax.barh(yy - 0.2, vb, height=0.4, color="tab:orange", label="nominal model")
    ax.barh(yy + 0.2, vf, height=0.4, color="tab:blue", label="final model")
    for y, r in zip(yy, base):
        ax.text(vb[y], y - 0.2, f" {r['rms']:.3g} {unit}".rstrip(), va="center", fontsize=6, color="0.3")
    ax.set_yticks(yy, names, fontsize=8)
    ax.invert_yaxis()
    ax.set_xlim(0, 1.15 * max(vb + vf + [1e-9]))   # room for the RMS labels
    ax.set_xlabel(f"residual RMS in the regime / RMS of {channel} over the record [%]")
    ax.set_title(f"residual of {channel} [{unit}] by operating regime (labels: nominal residual RMS)",
                 loc="left", fontsize=10)
    ax.legend(fontsize=8, loc="lower right")
    _save(fig, path)


def waterfall(path, steps) -> None:
    """Held-out NRMSE at each greedy step: baseline -> +effect 1 -> +effect 2."""
    labels = ["nominal"] + [f"+ {s.added}" for s in steps[1:]]
    vals = [100 * s.error for s in steps]
    fig, ax = plt.subplots(figsize=(1.8 * len(vals) + 3, 3.6))
    x = np.arange(len(vals))
    colors = ["tab:orange"] + ["tab:blue"] * (len(vals) - 1)
    ax.bar(x, vals, color=colors)
    for xi, v in zip(x, vals):
        ax.text(xi, v, f"{v:.2f} %", ha="center", va="bottom", fontsize=9)
    ax.set_ylim(0, 1.15 * max(max(vals), 1e-9))        # room for the value labels under the frame
    ax.set_xticks(x, labels, rotation=15 if len(vals) > 3 else 0, fontsize=9)
    ax.set_ylabel("held-out NRMSE [%]")
    ax.set_title("adding the missing effects (greedy, each significant on held-out data)")
    _save(fig, path)


def correlations(path, white: dict, channel: str) -> None:
    """Residual autocorrelation and cross-correlation with inputs, with the 99 % band."""
    n_cross = len(white["cross"])
    fig, axes = plt.subplots(1 + n_cross, 1, figsize=(8, 2.2 * (1 + n_cross)), squeeze=False)
    band = white["band"]
    ax = axes[0, 0]
    ax.stem(white["lags"], white["autocorr"], basefmt=" ")
    ax.axhspan(-band, band, color="tab:green", alpha=0.2)
    ax.set_title(f"residual autocorrelation ({channel}), 99 % band")
    for i, (name, xc) in enumerate(white["cross"].items(), 1):
        ax = axes[i, 0]
        ax.stem(xc["lags"], xc["xcorr"], basefmt=" ")
        ax.axhspan(-band, band, color="tab:green", alpha=0.2)
        ax.set_title(f"cross-correlation residual x {name}")
    axes[-1, 0].set_xlabel("lag [samples]")
    _save(fig, path)
