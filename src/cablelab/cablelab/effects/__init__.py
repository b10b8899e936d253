"""Effect registry (CONTRACT section 4): every physical effect is one
:class:`~cablelab.effects.base.Effect` registered by its stable id.

The generic per-actuator effects live in this package (``friction.py``, ``offset.py``,
``delay.py``) and apply to any plant whose datasets offer what they need (a plant declares
``capabilities`` in its :class:`~cablelab.registry.Plant`); plant-specific effects live in their
plant's package (``plants/<plant>/effects.py``) and register when it is imported. Looking up an
id imports the generic modules and every plant found by :mod:`cablelab.registry` once, so adding
an effect means adding one :class:`Effect` in one module (see docs/workbench.md "Adding an
effect").
"""
from __future__ import annotations

import importlib
import pkgutil

from ..errors import CablelabError
from .base import Effect, Param

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
        if not info.name.startswith("_") and info.name != "base":
            importlib.import_module(f"{__name__}.{info.name}")
    from ..registry import available_plants, get_plant

    for name in available_plants():
        try:
            get_plant(name)  # importing a plant registers its effects
        except CablelabError:
            pass


def _capabilities(plant: str | None) -> frozenset:
    from ..registry import get_plant

    try:
        return get_plant(plant).capabilities if plant else frozenset()
    except CablelabError:
        return frozenset()


def all_effects() -> dict[str, Effect]:
    """id -> Effect of every registered effect."""
    _load_all()
    return dict(_REGISTRY)


def effects_for(plant: str) -> list[str]:
    """Ids of the effects applicable to ``plant`` (sorted)."""
    caps = _capabilities(plant)
    return sorted(e.id for e in all_effects().values() if e.applies_to(plant, caps))


def get_effect(effect_id: str, plant: str | None = None) -> Effect:
    """The effect with this id, checked against the plant.

    Raises:
        CablelabError: unknown id, or an id that does not apply to ``plant``; the message lists
            the valid ids.
    """
    eff = _REGISTRY.get(effect_id)
    if eff is None:
        eff = all_effects().get(effect_id)
    if eff is None:
        valid = effects_for(plant) if plant else sorted(all_effects())
        where = f" for plant {plant}" if plant else ""
        raise CablelabError(f"unknown effect {effect_id!r}; valid effects{where}: {', '.join(valid)}")
    if plant is not None and not eff.applies_to(plant, _capabilities(plant)):
        raise CablelabError(f"effect {effect_id!r} does not apply to plant {plant} (it applies to "
                            f"{eff.applies_doc()}); valid effects for {plant}: "
                            f"{', '.join(effects_for(plant))}")
    return eff


__all__ = ["Effect", "Param", "all_effects", "effects_for", "get_effect", "register"]
