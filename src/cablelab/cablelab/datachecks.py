"""Data a diagnosis cannot handle, refused before any ranking.

Every check raises a one-line :class:`~cablelab.errors.CablelabError` naming the problem (file,
channel, value) and the recording that would fix it, instead of a confident ranking of noise:

* :func:`check_raw_series` (on raw arrays, before conditioning): non-monotonic time stamps, long
  runs of NaN samples;
* :func:`check_dataset` (on the conditioned dataset): too few usable samples, a constant output
  channel, a drive that (almost) never moves.
"""
from __future__ import annotations

import numpy as np

from .errors import CablelabError

#: fewest usable (valid, moving) samples for a diagnosis
MIN_SAMPLES = 500
#: longest tolerated NaN run: this many samples or this share of the record, whichever is larger
MAX_NAN_RUN, MAX_NAN_SHARE = 20, 0.01
#: a channel whose spread is below this fraction of its magnitude (or exactly 0) is constant
CONSTANT_REL = 1e-9
#: least share of samples outside the zero-speed zone
MIN_MOVING_SHARE = 0.05


def longest_nan_run(x: np.ndarray) -> tuple[int, int]:
    """``(length, start index)`` of the longest run of rows of ``x`` (N,) or (N, k) with a NaN."""
    bad = ~np.isfinite(np.asarray(x, dtype=float).reshape(len(x), -1)).all(axis=1)
    if not bad.any():
        return 0, -1
    d = np.diff(np.concatenate([[0], bad.astype(int), [0]]))
    starts, ends = np.flatnonzero(d == 1), np.flatnonzero(d == -1)
    k = int(np.argmax(ends - starts))
    return int(ends[k] - starts[k]), int(starts[k])


def check_raw_series(t: np.ndarray, source: str, **signals: np.ndarray) -> None:
    """Refuse stamps that run backwards and long NaN runs (raw arrays, before resampling).

    Raises:
        CablelabError: naming the signal, where, and what to re-record.
    """
    t = np.asarray(t, dtype=float)
    fin = np.isfinite(t)
    dt = np.diff(t[fin])
    if dt.size and np.any(dt < 0):
        i = int(np.flatnonzero(dt < 0)[0])
        raise CablelabError(f"{source}: time stamps are not monotonic (sample {i + 1} goes back "
                            f"{-dt[i]:.3g} s at t = {t[fin][i]:.3f} s): record with one clock "
                            "(header stamps of a single publisher) or re-stamp the messages")
    n = t.size
    limit = max(MAX_NAN_RUN, int(MAX_NAN_SHARE * n))
    for name, x in (("time", t), *signals.items()):
        if x is None:
            continue
        run, start = longest_nan_run(x)
        if run > limit:
            t0 = t[start] if np.isfinite(t[start]) else float("nan")
            raise CablelabError(f"{source}: {name} has a run of {run} missing (NaN) samples from "
                                f"t = {t0:.3f} s (more than {limit}): fix the sensor dropout or "
                                "record a run without the gap")


def check_dataset(ds) -> None:
    """Refuse a conditioned dataset that cannot support a diagnosis.

    Raises:
        CablelabError: too few usable samples, a constant output channel, no motion.
    """
    src = ds.source or ds.plant
    ok = ds.valid & np.isfinite(ds.y).all(axis=1)
    # a plant may mark channels its record does not excite (``signals["excited"]``, one bool per
    # channel): those are set aside on purpose, not a stuck sensor
    excited = np.asarray(ds.signals.get("excited", np.ones(ds.n_channels, bool)), bool).reshape(-1)
    if excited.size == ds.n_channels and not excited.any():
        raise CablelabError(f"{src}: no output channel is excited ({', '.join(ds.channels)}): record "
                            "a run with motion")
    # and channels without an effort sensor (``signals["driven"]`` False: an unactuated joint's
    # zero-force equation, y = 0 by physics, not a stuck sensor)
    driven = np.asarray(ds.signals.get("driven", np.ones(ds.n_channels, bool)), bool).reshape(-1)
    for c, ch in enumerate(ds.channels):
        if excited.size == ds.n_channels and not excited[c]:
            continue
        if driven.size == ds.n_channels and not driven[c]:
            continue
        y = ds.y[np.isfinite(ds.y[:, c]), c]
        spread = float(np.ptp(y)) if y.size else 0.0
        if spread <= CONSTANT_REL * max(float(np.max(np.abs(y))) if y.size else 0.0, 1e-300):
            val = float(y[0]) if y.size else float("nan")
            raise CablelabError(f"{src}: channel {ch} is constant ({val:g} {ds.units[c]}): the "
                                "effort sensor is not recorded or stuck; record the measured effort")
    share = ds.signals.get("rest_share")
    if share is not None and 1.0 - float(share) < MIN_MOVING_SHARE:
        raise CablelabError(f"{src}: the drive moves in only {100 * (1 - float(share)):.1f} % of the "
                            "samples (the rest is inside the zero-speed zone): no parameter of the "
                            "motion is excited; record moves (point-to-point at several speeds, "
                            "both directions)")
    if int(ok.sum()) < MIN_SAMPLES:
        raise CablelabError(f"{src}: only {int(ok.sum())} usable samples (need {MIN_SAMPLES}; "
                            f"{ds.n} recorded): record a longer run (a few seconds of motion)")
