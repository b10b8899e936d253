"""Diagnosis: compare metrics (:mod:`.metrics`), where the model fails (:mod:`.localise`,
:mod:`.whiteness`), which effect is missing and the greedy waterfall (:mod:`.ranking`)."""
from .localise import derived_regimes, residual_by_regime, worst_segments
from .metrics import channel_metrics, nrmse
from .ranking import cv_error, fold_indices, greedy, rank_candidates, significance
from .result import Candidate, Diagnosis, Step
from .whiteness import whiteness

__all__ = ["Candidate", "Diagnosis", "Step", "channel_metrics", "cv_error", "derived_regimes", "fold_indices", "greedy",
           "nrmse", "rank_candidates", "residual_by_regime",
           "significance", "whiteness", "worst_segments"]
