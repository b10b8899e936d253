"""Plant ``leg``: the parallel-elastic hopping leg of paper 003 (spec 003_leg.md). Importing the
package registers it (:mod:`cablelab.registry`), its effects and its experiment design
(:mod:`.excite`).

Modules: :mod:`.hybrid` (phase model, guards, impact maps), :mod:`.mjcf` and :mod:`.sim` (MuJoCo
plant with event-located switches), :mod:`.reference` (scipy oracle for tests), :mod:`.estimator`,
:mod:`.control`, :mod:`.identify` (staged NMSE identification, k-fold CV), :mod:`.effects`,
:mod:`.dataset` (workbench inverse model), :mod:`.description` (``leg:`` section), :mod:`.plant`.
Docs: README.md in this folder.
"""
from ...excite import register_exciter
from ...registry import register_plant
from . import effects  # noqa: F401  (registers the leg effects)
from .excite import EXCITER
from .plant import PLANT

register_plant(PLANT)
register_exciter(PLANT.name, EXCITER)
