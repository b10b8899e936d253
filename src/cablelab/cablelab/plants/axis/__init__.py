"""The axis plant: importing the package registers it (:mod:`cablelab.registry`) and its effects.

Docs: README.md in this folder."""
from ...registry import register_plant
from . import effects  # noqa: F401  (registers the axis effects)
from .plant import PLANT

register_plant(PLANT)
