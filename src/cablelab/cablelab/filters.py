"""Zero-phase low-pass filtering along time, shared by conditioning (derivatives of motion),
velocity (quantization-aware derivatives) and the plants."""
from __future__ import annotations

import numpy as np
import scipy.signal

from .errors import CablelabError

__all__ = ["lowpass"]


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
