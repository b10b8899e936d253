"""Plant ``pendulum``: a toy damped pendulum driven at its hinge, written outside cablelab to prove
that adding a plant touches one folder (test_toy_plant.py: found through the entry point, then
simulated, recorded, diagnosed and reported with no edit anywhere else).

The one registration place: registers :data:`.plant.PLANT` and, by importing :mod:`.effects`,
the plant's effects. Found through the ``cablelab.plants`` entry-point group (pyproject.toml:
``pendulum = "pendulum_plant"``); nothing else may register.
"""
from __future__ import annotations

from cablelab.registry import register_plant

from . import effects  # noqa: F401  (registers the plant's effects)
from .plant import PLANT

register_plant(PLANT)
