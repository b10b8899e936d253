"""Plant registry: what the workbench needs to know about each plant.

A plant module ``cablelab/plants/<name>.py`` builds a :class:`Plant` and calls
:func:`register_plant` at import. :func:`get_plant` imports the module named for the plant on
first use, so a new plant is one new module (see docs/workbench.md "Adding a plant").
"""
from __future__ import annotations

import importlib
from dataclasses import dataclass
from typing import Callable

from ..errors import CablelabError

_REGISTRY: dict[str, "Plant"] = {}


@dataclass(frozen=True)
class Plant:
    """A plant as seen by the workbench.

    Args:
        name: plant id (``axis``, ``crane``, ``cdpr``), = ``description.plant``.
        topics: required ``(topic, type)`` pairs in a bag (checked before loading).
        dataset: ``fn(bag, description, options) -> Dataset``: conditioned signals, output
            channels, actuator map and velocities, regimes. ``options`` is a dict of plant options
            from the command line (``{"conditioning": Conditioning, "tensions": "dynamometer"}``).
        baseline: ``fn(description) -> tuple of effect ids`` of the nominal model.
        candidates: ``fn(description) -> tuple of effect ids`` that diagnose may try (the model's
            own effects are skipped).
        channels_doc: one line describing the output channels (for docs and reports).
        simulate: optional free-run comparison ``fn(ds, params) -> dict`` (``{"channel",
            "nrmse", "max_abs", "pearson", ...}``) shown by ``compare`` next to the inverse model.
        simulation_fit: optional simulation-based fit ``fn(ds, start_params, *, objective,
            progress=False) ->``
            :class:`~cablelab.fit.simulation.SimulationFit` (``identify --simulation nmse|pearson``).
    """

    name: str
    topics: tuple[tuple[str, str], ...]
    dataset: Callable
    baseline: Callable
    candidates: Callable
    channels_doc: str = ""
    simulate: Callable | None = None
    simulation_fit: Callable | None = None


def register_plant(plant: Plant) -> Plant:
    _REGISTRY[plant.name] = plant
    return plant


def get_plant(name: str) -> Plant:
    """The registered plant (imports ``cablelab.plants.<name>``).

    Raises:
        CablelabError: no workbench model for that plant.
    """
    if name not in _REGISTRY:
        try:
            importlib.import_module(f"{__name__}.{name}")
        except ModuleNotFoundError as exc:
            if exc.name != f"{__name__}.{name}":
                raise
        if name not in _REGISTRY:
            raise CablelabError(f"plant {name!r} has no workbench model (available: "
                                f"{', '.join(available_plants()) or 'none'})")
    return _REGISTRY[name]


def available_plants() -> list[str]:
    """Plants with a workbench module (registered or importable)."""
    import pkgutil

    names = {m.name for m in pkgutil.iter_modules(__path__) if not m.name.startswith("_")}
    return sorted(n for n in names | set(_REGISTRY) if "_" not in n or n in _REGISTRY)


__all__ = ["Plant", "available_plants", "get_plant", "register_plant"]
