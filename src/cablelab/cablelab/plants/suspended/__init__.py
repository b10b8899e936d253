"""Plant ``suspended``: cable-suspended dual-arm platforms LiCAS and CRANEbot (paper 000,
spec 000_suspended.md). Importing the package registers it (:mod:`cablelab.registry`) and its
effects. Modules:

* :mod:`.params` - parameter sets ``repo`` (default) and ``table5`` per variant, defects D1-D8;
* :mod:`.description` - the ``suspended:`` description section;
* :mod:`.mjcf` - virtual-joint MuJoCo chain J7-J12 with virtual PD, and the truth plants;
* :mod:`.sim` - rollout-based simulation; :mod:`.reference` - planar solve_ivp reference;
* :mod:`.swing` - swing/yaw estimate from the platform pose (batch + live);
* :mod:`.control` - arm PD + gravity under the platform attitude, Fig. 7, sway damping;
* :mod:`.identify` - Pearson (000 eq. 3-7) and NMSE identification on mujoco.minimize/rollout;
* :mod:`.plant`, :mod:`.dataset`, :mod:`.effects` - the workbench plug-in (compare / diagnose /
  report);
* :mod:`.bag` - writing simulated runs as contract bags.

Docs: README.md in this folder.
"""
from ...registry import register_plant
from . import effects  # noqa: F401  (registers the suspended effects)
from .plant import PLANT

register_plant(PLANT)
