"""The cdpr plant: importing the package registers it (:mod:`cablelab.registry`), its effects and
its experiment design.

Docs: README.md in this folder."""
from ...excite import register_exciter
from ...registry import register_plant
from . import effects  # noqa: F401  (registers the cdpr effects)
from .excite import EXCITER
from .plant import PLANT

register_plant(PLANT)
register_exciter(PLANT.name, EXCITER)
