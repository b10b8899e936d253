"""How well one fit matches the measurement: metrics per channel, residual by operating regime
and residual whiteness, computed once for ``cablelab compare`` and the report alike."""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from ..dataset import Dataset
from .localise import derived_regimes, residual_by_regime
from .metrics import channel_metrics
from .whiteness import whiteness


@dataclass(frozen=True)
class FitMetrics:
    """The quality of one fit (:func:`fit_metrics`).

    Attributes:
        y_meas: (N, C) measured output aligned with the model (after its data transforms), NaN
            where not valid.
        channels: one :func:`~cablelab.diagnose.metrics.channel_metrics` dict per channel.
        regimes: :func:`~cablelab.diagnose.localise.residual_by_regime` rows (empty when not
            asked for).
        whiteness: channel -> :func:`~cablelab.diagnose.whiteness.whiteness` of its residual
            (empty when not asked for).
    """

    y_meas: np.ndarray
    channels: list
    regimes: list
    whiteness: dict


def residual_decimation(ds: Dataset) -> int:
    """Samples per independent sample of a residual of signals low-passed at the dataset's
    cut-off (``signals["cutoff_hz"]``): fs / (2 f_c); 1 when unknown."""
    fc = ds.signals.get("cutoff_hz")
    return max(1, int(ds.fs / (2.0 * float(fc)))) if fc else 1


def fit_metrics(ds: Dataset, fit, *, regimes: dict | None = None, with_regimes: bool = True,
                with_whiteness: bool = True) -> FitMetrics:
    """Metrics of ``fit`` (an :class:`~cablelab.fit.Identification` on ``ds``).

    Args:
        regimes: the dataset's :func:`~cablelab.diagnose.localise.derived_regimes` when already
            computed (several fits of one dataset).
        with_regimes: also the residual by operating regime (else ``regimes`` is empty).
        with_whiteness: also test the residual of every channel for whiteness.
    """
    y_meas = np.where(fit.valid[:, None], fit.residual + fit.y_hat, np.nan)
    by_regime = []
    if with_regimes:
        regimes = derived_regimes(ds) if regimes is None else regimes
        by_regime = residual_by_regime(fit.residual, y_meas, regimes, ds.channels)
    white = {}
    if with_whiteness:
        dec = residual_decimation(ds)
        white = {ch: whiteness(fit.residual[:, c], ds.inputs, decimate=dec)
                 for c, ch in enumerate(ds.channels)}
    return FitMetrics(y_meas, channel_metrics(y_meas, fit.y_hat, fit.valid), by_regime, white)
