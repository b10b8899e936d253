"""The pendulum's own effects (regressors of the inverse model ``tau = I qdd + m l g sin q``),
registered by id; the generic joint effects (friction, offset, delay) come with cablelab."""
from __future__ import annotations

import numpy as np

from cablelab.effects import register
from cablelab.effects.base import Effect, Param

#: the effect ids of the nominal model (the plant's ``baseline``)
NOMINAL = ("pendulum_inertia", "pendulum_gravity")

register(Effect(
    id="pendulum_inertia", plants=("pendulum",),
    params=(Param("I", "kg m^2", 0.0, 0.0, np.inf, "inertia about the hinge"),),
    explanation="torque to accelerate the body about the hinge (I qdd)",
    signature="residual follows the acceleration", reference="plant template",
    regressor=lambda ds: ds.require_signal("qdd").reshape(ds.n, 1, 1)))
register(Effect(
    id="pendulum_gravity", plants=("pendulum",),
    params=(Param("ml", "kg m", 0.0, -np.inf, np.inf, "gravity moment m l"),),
    explanation="gravity pulls the bob down with torque m l g sin(q)",
    signature="residual follows sin(q)", reference="toy plant (test)",
    regressor=lambda ds: (ds.gravity * np.sin(ds.require_signal("q"))).reshape(ds.n, 1, 1)))
