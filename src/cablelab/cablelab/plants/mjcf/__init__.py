"""The ``mjcf`` plant: any machine from its MuJoCo model (MJCF or URDF). Importing the package
registers it (:mod:`cablelab.registry`) and its effects. Docs: README.md in this folder."""
from ...excite import register_exciter
from ...registry import register_plant
from . import effects  # noqa: F401  (registers the effect ids)
from .excite import EXCITER
from .plant import PLANT

register_plant(PLANT)
register_exciter(PLANT.name, EXCITER)
