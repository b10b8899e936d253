"""Where the model fails: residual in time (worst segments) and by operating regime.

Regimes derived from every dataset's actuator velocities (``Dataset.act_vel``) and
accelerations: velocity sign (moving +, moving -, at rest), near a velocity reversal, and
acceleration level; plants add their own (position bins, pose regions) in ``Dataset.regimes``.
"""
from __future__ import annotations

import numpy as np

from ..dataset import Dataset

#: at rest: |v| below this fraction of the 99th-percentile speed of that actuator
REST_FRACTION = 0.02
#: "near reversal": within this time of a velocity sign change, s
REVERSAL_WINDOW_S = 0.05


def worst_segments(t: np.ndarray, residual: np.ndarray, y: np.ndarray, channels, *,
                   window_s: float | None = None, count: int = 5) -> list[dict]:
    """The ``count`` non-overlapping windows with the largest RMS residual, all channels pooled.

    Args:
        t: (N,) s; residual, y: (N, C) (NaN = invalid); channels: names.
        window_s: window length, s (default: duration / 50, at least 10 samples).
    Returns:
        ``[{"channel", "t_start", "t_end", "error", "rms"}]`` worst first; ``error`` = rms of the
        residual in the window / rms of the channel over the record (an NRMSE of that window).
    """
    n, c = residual.shape
    if n < 2:
        return []
    dt = float(np.median(np.diff(t)))
    win = max(10, int(round((window_s or (t[-1] - t[0]) / 50.0) / dt)))
    win = min(win, n)
    e2 = np.where(np.isfinite(residual), residual**2, 0.0)
    cnt = np.isfinite(residual).astype(float)
    rms_y = np.sqrt(np.nanmean(np.where(np.isfinite(residual), y, np.nan) ** 2, axis=0))
    cs = np.vstack([np.zeros((1, c)), np.cumsum(e2, axis=0)])
    cc = np.vstack([np.zeros((1, c)), np.cumsum(cnt, axis=0)])
    ssum = cs[win:] - cs[:-win]
    scnt = cc[win:] - cc[:-win]
    rms = np.sqrt(ssum / np.maximum(scnt, 1))
    rms = np.where(scnt >= win // 2, rms, 0.0)
    score = rms / np.where(rms_y > 0, rms_y, 1.0)  # (n - win + 1, C)
    out = []
    taken = np.zeros(score.shape[0], dtype=bool)
    for _ in range(count):
        s = np.where(taken[:, None], -1.0, score)
        i, ch = np.unravel_index(int(np.argmax(s)), s.shape)
        if s[i, ch] <= 0:
            break
        out.append({"channel": channels[ch], "t_start": float(t[i]), "t_end": float(t[i + win - 1]),
                    "error": float(score[i, ch]), "rms": float(rms[i, ch])})
        taken[max(0, i - win + 1): i + win] = True
    return out


def derived_regimes(ds: Dataset) -> dict[str, np.ndarray]:
    """Velocity sign, reversal and acceleration-level regimes from ``act_vel`` (per actuator),
    plus the plant's own ``ds.regimes``. Each value is an (N,) label array."""
    out: dict[str, np.ndarray] = {}
    if ds.act_vel is not None:
        v = ds.act_vel
        acc = np.gradient(v, ds.t, axis=0) if ds.n > 2 else np.zeros_like(v)
        vmax = np.percentile(np.abs(v), 99, axis=0)
        rest = np.abs(v) <= REST_FRACTION * np.where(vmax > 0, vmax, 1.0)
        sgn = np.where(rest, 0, np.sign(v)).astype(int)
        half = max(1, int(round(REVERSAL_WINDOW_S / ds.dt)))
        kernel = np.ones(2 * half + 1)
        for j, name in enumerate(ds.actuators):
            sfx = f" ({name})" if len(ds.actuators) > 1 else ""
            out[f"velocity{sfx}"] = np.array(["at rest", "moving +", "moving -"])[np.where(
                sgn[:, j] == 0, 0, np.where(sgn[:, j] > 0, 1, 2))]
            s = np.sign(v[:, j])
            flips = np.zeros(ds.n)
            flips[1:] = (s[1:] * s[:-1] < 0) | ((s[1:] != s[:-1]) & (s[1:] != 0) & (s[:-1] != 0))
            # (centred window; "same" would return the kernel's length for a record shorter than it)
            near = np.convolve(flips, kernel)[half:half + ds.n] > 0
            out[f"reversal{sfx}"] = np.where(near, "near reversal", "away from reversal")
            a = np.abs(acc[:, j])
            hi = a > np.median(a)
            out[f"acceleration{sfx}"] = np.where(hi, "high |acc|", "low |acc|")
    out.update(ds.regimes)
    return out


def factorise_regimes(regimes: dict[str, np.ndarray]) -> dict[str, tuple[np.ndarray, np.ndarray]]:
    """Each regime's label array as ``(sorted distinct labels, (N,) index into them)``: what
    :func:`residual_by_regime` works on, computed once when it is called for many residuals of
    the same dataset (string labels are slow to compare and sort)."""
    return {k: np.unique(np.asarray(v), return_inverse=True) for k, v in regimes.items()}


def residual_by_regime(residual: np.ndarray, y: np.ndarray, regimes: dict, channels) -> list[dict]:
    """Residual RMS and mean per regime label, normalised by the channel RMS.

    Args:
        regimes: name -> (N,) label array, or the ``(labels, index)`` pair of
            :func:`factorise_regimes`.
    Returns:
        ``[{"regime", "label", "channel", "n", "rms", "mean", "nrmse"}]``.
    """
    ok = np.isfinite(residual).all(axis=1)
    rms_y = np.sqrt(np.mean(y[ok] ** 2, axis=0))
    out = []
    for rname, labels in regimes.items():
        uniq, code = labels if isinstance(labels, tuple) else \
            np.unique(np.asarray(labels), return_inverse=True)
        code = np.asarray(code).reshape(-1)
        for k in np.flatnonzero(np.bincount(code[ok], minlength=len(uniq))):
            lab = uniq[k]
            m = ok & (code == k)
            r = residual[m]
            for c, ch in enumerate(channels):
                rms = float(np.sqrt(np.mean(r[:, c] ** 2)))
                out.append({"regime": rname, "label": str(lab), "channel": ch, "n": int(m.sum()),
                            "rms": rms, "mean": float(np.mean(r[:, c])),
                            "nrmse": rms / float(rms_y[c]) if rms_y[c] > 0 else None})
    return out
