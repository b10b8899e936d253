"""The axis plant: importing the package registers it (:mod:`cablelab.registry`) and its effects.

Docs: README.md in this folder."""
from . import effects, plant  # noqa: F401  (registration at import)
from .plant import AXIS

PLANT = AXIS
