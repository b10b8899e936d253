"""Identification: linear least squares with base parameters, bounds and uncertainty
(:mod:`.linear`), separable LS for nonlinear parameters (:mod:`.identification`), and simulation-based
fits on mujoco.minimize with the Pearson (000 eq. 3-7) and NMSE (003 eq. 28) objectives
(:mod:`.simulation`)."""
from .identification import Identification, evaluate, identify
from .linear import LinearFit, solve_linear

__all__ = ["Identification", "LinearFit", "evaluate", "identify", "solve_linear"]
