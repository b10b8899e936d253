"""Effect registry (CONTRACT section 4): every physical effect is one :class:`~cablelab.model.Effect`
registered by its stable id.

Effects live in the modules of this package and register themselves at import with
:func:`register`: the generic per-actuator effects in ``friction.py``, ``offset.py``,
``delay.py``; plant-specific effects in a module named for the plant (``axis.py``, ``cdpr.py``,
``crane.py``). Every module of the package is imported on first lookup, so adding an effect means
adding one :class:`Effect` in one module (see docs/workbench.md "Adding an effect").
"""
from __future__ import annotations

import importlib
import pkgutil

from ..errors import CablelabError
from ..model import Effect

_REGISTRY: dict[str, Effect] = {}
_LOADED = False


def register(effect: Effect) -> Effect:
    """Add an effect to the registry (id must be new). Returns it, for module-level use."""
    old = _REGISTRY.get(effect.id)
    if old is not None and old is not effect and old.reference != effect.reference:
        raise RuntimeError(f"effect id {effect.id!r} registered twice")
    _REGISTRY[effect.id] = effect
    return effect


def _load_all() -> None:
    global _LOADED
    if _LOADED:
        return
    _LOADED = True
    for info in pkgutil.iter_modules(__path__):
        if not info.name.startswith("_"):
            importlib.import_module(f"{__name__}.{info.name}")


def all_effects() -> dict[str, Effect]:
    """id -> Effect of every registered effect."""
    _load_all()
    return dict(_REGISTRY)


def effects_for(plant: str) -> list[str]:
    """Ids of the effects applicable to ``plant`` (sorted)."""
    return sorted(e.id for e in all_effects().values() if e.applies_to(plant))


def get_effect(effect_id: str, plant: str | None = None) -> Effect:
    """The effect with this id, checked against the plant.

    Raises:
        CablelabError: unknown id, or an id that does not apply to ``plant``; the message lists
            the valid ids.
    """
    effects = all_effects()
    eff = effects.get(effect_id)
    if eff is None:
        valid = effects_for(plant) if plant else sorted(effects)
        where = f" for plant {plant}" if plant else ""
        raise CablelabError(f"unknown effect {effect_id!r}; valid effects{where}: {', '.join(valid)}")
    if plant is not None and not eff.applies_to(plant):
        raise CablelabError(f"effect {effect_id!r} does not apply to plant {plant} (it applies to "
                            f"{', '.join(eff.plants)}); valid effects for {plant}: "
                            f"{', '.join(effects_for(plant))}")
    return eff


__all__ = ["Effect", "all_effects", "effects_for", "get_effect", "register"]
