"""The plant's own effects (regressors of the inverse model ``tau = sum_k theta_k phi_k``),
registered by id; the generic joint effects (friction, offset, delay) come with cablelab."""
from __future__ import annotations

import numpy as np

from cablelab.effects import register
from cablelab.effects.base import Effect, Param

register(Effect(
    id="pendulum_inertia", plants=("pendulum",),
    params=(Param("I", "kg m^2", 0.0, 0.0, np.inf, "inertia about the hinge"),),
    explanation="torque to accelerate the body about the hinge (I qdd)",
    signature="residual follows the acceleration", reference="plant template",
    regressor=lambda ds: ds.require_signal("qdd").reshape(ds.n, 1, 1)))
