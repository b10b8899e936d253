"""cablelab's own plants, one subpackage each (``axis/``, ``crane/``, ``cdpr/``, ...).

Each subpackage holds everything of its plant: description section, model, kinematics/dynamics,
effects, MuJoCo truth simulator, live estimator and controller laws, node adapters (``nodes/``),
demo part, default data and its docs page (``README.md``). Importing a subpackage registers the
plant in :mod:`cablelab.registry`, which finds them (and plants of other distributions, through
the ``cablelab.plants`` entry-point group). See docs/architecture.md "Adding a plant".
"""
from ..registry import Plant, available_plants, get_plant, register_plant

__all__ = ["Plant", "available_plants", "get_plant", "register_plant"]
