"""Plant ``pendulum``: a hinge of inertia I driven at its joint (replace with what the machine is).

The one registration place: registers :data:`.plant.PLANT` and, by importing :mod:`.effects`,
the plant's effects. Found through the ``cablelab.plants`` entry-point group (pyproject.toml:
``pendulum = "pendulum_plant"``); nothing else may register.
"""
from __future__ import annotations

from cablelab.registry import register_plant

from . import effects  # noqa: F401  (registers the plant's effects)
from .plant import PLANT

register_plant(PLANT)
