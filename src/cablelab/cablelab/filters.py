"""Zero-phase low-pass filtering along time, shared by conditioning (derivatives of motion),
velocity (quantization-aware derivatives) and the plants."""
from __future__ import annotations

import numpy as np
import scipy.signal

from .errors import CablelabError

__all__ = ["lowpass", "check_cutoff"]


def lowpass(x: np.ndarray, fs: float, cutoff_hz: float, order: int = 4) -> np.ndarray:
    """Zero-phase Butterworth low-pass along time (axis 0) (003 sec. 4: 3rd order at 15 Hz;
    EMPS: 4th order at 100 Hz).

    Args:
        x: (N, ...) signal; fs: sample rate, Hz; cutoff_hz: cut-off, Hz; order: filter order.
    """
    x = np.asarray(x, dtype=float)
    if not 0 < cutoff_hz < fs / 2:
        raise CablelabError(f"filter cut-off {cutoff_hz:g} Hz (--cutoff) must be between 0 and fs/2 = "
                            f"{fs / 2:g} Hz")
    sos = scipy.signal.butter(order, cutoff_hz, fs=fs, output="sos")
    padlen = min(x.shape[0] - 1, 3 * (2 * len(sos) + 1) * 3)
    return scipy.signal.sosfiltfilt(sos, x, axis=0, padlen=padlen)


def check_cutoff(cutoff_hz: float, fs: float, n: int) -> None:
    """A user's cut-off for a record of ``n`` samples at ``fs`` Hz: between one cycle over the
    record (lower, it filters all the motion out, and the filter itself degenerates: a
    Butterworth at 1e-9 Hz is singular) and fs/2. One-line error naming ``--cutoff`` otherwise."""
    lowest = fs / max(int(n), 1)
    if not lowest <= cutoff_hz < fs / 2:
        raise CablelabError(f"--cutoff {cutoff_hz:g} Hz: expected a cut-off between {lowest:.3g} Hz "
                            f"(one cycle over the {n / fs:.3g} s record) and fs/2 = {fs / 2:g} Hz")
