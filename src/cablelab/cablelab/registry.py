"""Plant registry: what the rest of cablelab knows about each plant, and how plants are found.

A plant is one Python package. cablelab's own plants are the subpackages of
:mod:`cablelab.plants` (``plants/axis/``, ``plants/crane/``, ``plants/cdpr/``, ...); a plant in
another distribution is announced by an entry point in the group ``cablelab.plants``
(``myplant = mypackage.myplant``). Importing the package registers its :class:`Plant` with
:func:`register_plant` (and its effects with :func:`cablelab.effects.register`). No module of the
core names a plant: the description loader, the topic sets, the recorder, the importer, the
workbench and the node executables all ask this registry (see docs/architecture.md). What a plant
must offer is :class:`~cablelab.plant_interface.PlantInterface`, checked at registration.
"""
from __future__ import annotations

import importlib
import importlib.util
import pkgutil
from typing import Callable

from .errors import CablelabError
from .plant_interface import Plant, PlantInterface, missing_members

#: entry-point group under which other distributions announce plant packages
ENTRY_POINT_GROUP = "cablelab.plants"
#: the package holding cablelab's own plants (one subpackage each)
BUILTIN_PACKAGE = "cablelab.plants"

_REGISTRY: dict[str, PlantInterface] = {}


def lazy_hook(module: str, name: str) -> Callable:
    """A plant hook that imports ``module`` only when first called and calls its ``name`` (for
    hooks whose module is heavy, e.g. the 3D markers with MuJoCo, not needed at registration)."""

    def hook(*args, **kwargs):
        return getattr(importlib.import_module(module), name)(*args, **kwargs)

    hook.__qualname__ = f"{module}.{name}"
    return hook


def register_plant(plant: PlantInterface) -> PlantInterface:
    """Register a plant (at import of its package). Returns it.

    Raises:
        CablelabError: ``plant`` does not satisfy :class:`~cablelab.plant_interface.PlantInterface`
            (one line naming what it lacks).
    """
    missing = missing_members(plant)
    if missing:
        name = getattr(plant, "name", None)
        raise CablelabError(f"plant {name!r} does not satisfy the plant interface "
                            f"(cablelab.plant_interface.PlantInterface): it lacks {', '.join(missing)}")
    _REGISTRY[plant.name] = plant
    return plant


_DISCOVERED: dict[tuple, dict[str, str]] = {}


def _discovered() -> dict[str, str]:
    """plant name -> package of the subpackages of :mod:`cablelab.plants` and the entry points.

    Cached per ``sys.path`` (reading every installed distribution's entry points took ~5 ms, twice
    per loaded bag: a tenth of a short bag's whole diagnosis in ``cablelab batch``)."""
    import sys

    key = tuple(sys.path)
    if key not in _DISCOVERED:
        _DISCOVERED.clear()
        _DISCOVERED[key] = _discover()
    return dict(_DISCOVERED[key])


def _discover() -> dict[str, str]:
    found: dict[str, str] = {}
    spec = importlib.util.find_spec(BUILTIN_PACKAGE)
    for info in pkgutil.iter_modules(spec.submodule_search_locations or []):
        if info.ispkg and not info.name.startswith("_"):
            found[info.name] = f"{BUILTIN_PACKAGE}.{info.name}"
    from importlib.metadata import entry_points

    for ep in entry_points(group=ENTRY_POINT_GROUP):
        found.setdefault(ep.name, ep.value)
    return found


def plant_packages() -> dict[str, str]:
    """plant name -> Python package, for every plant that can be found: the subpackages of
    :mod:`cablelab.plants`, the entry points of the group ``cablelab.plants``, and plants
    registered by code that imported them some other way."""
    found = _discovered()
    for name, plant in _REGISTRY.items():
        found.setdefault(name, plant.package)
    return found


def available_plants() -> list[str]:
    """Names of every plant that can be found (registered or importable), sorted."""
    return sorted(plant_packages())


def get_plant(name: str) -> PlantInterface:
    """The registered plant ``name``, importing its package on first use.

    Raises:
        CablelabError: no such plant (the message lists the available ones).
    """
    if name not in _REGISTRY:
        package = _discovered().get(name) if isinstance(name, str) else None
        if not package:
            raise CablelabError(f"plant {name!r} has no workbench model (available: "
                                f"{', '.join(available_plants()) or 'none'})")
        importlib.import_module(package)
        if name not in _REGISTRY:
            raise CablelabError(f"plant package {package} registers no plant {name!r}")
    if not _REGISTRY[name].package:
        import dataclasses

        plant = _REGISTRY[name]
        package = _discovered().get(name) or plant.dataset.__module__.rsplit(".", 1)[0]
        if dataclasses.is_dataclass(plant):
            _REGISTRY[name] = dataclasses.replace(plant, package=package)
        else:
            plant.package = package
    return _REGISTRY[name]


def plant_module(name: str, module: str):
    """The module ``<plant package>.<module>`` of plant ``name`` (e.g. its ``nodes``)."""
    plant = get_plant(name)
    return importlib.import_module(f"{plant.package}.{module}")


__all__ = ["ENTRY_POINT_GROUP", "Plant", "PlantInterface", "available_plants", "get_plant", "lazy_hook",
           "plant_module", "plant_packages", "register_plant"]
