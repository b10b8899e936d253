"""Plant registry: what the rest of cablelab knows about each plant, and how plants are found.

A plant is one Python package. cablelab's own plants are the subpackages of
:mod:`cablelab.plants` (``plants/axis/``, ``plants/crane/``, ``plants/cdpr/``, ...); a plant in
another distribution is announced by an entry point in the group ``cablelab.plants``
(``myplant = mypackage.myplant``). Importing the package registers its :class:`Plant` with
:func:`register_plant` (and its effects with :func:`cablelab.effects.register`). No module of the
core names a plant: the description loader, the topic sets, the recorder, the importer, the
workbench and the node executables all ask this registry (see docs/architecture.md).
"""
from __future__ import annotations

import importlib
import importlib.util
import pkgutil
from dataclasses import dataclass, field
from typing import Callable, Mapping

from .errors import CablelabError

#: entry-point group under which other distributions announce plant packages
ENTRY_POINT_GROUP = "cablelab.plants"
#: the package holding cablelab's own plants (one subpackage each)
BUILTIN_PACKAGE = "cablelab.plants"

_REGISTRY: dict[str, "Plant"] = {}


@dataclass(frozen=True)
class Plant:
    """A plant as seen by the workbench, the description loader, the recorder and the nodes.

    Args:
        name: plant id (``axis``, ``crane``, ``cdpr``, ...) = ``description.plant`` = the name
            of its description section.
        topics: ``(topic, type)`` pairs a bag must hold for the workbench (checked first).
        dataset: ``fn(bag, description, options) -> Dataset``: conditioned signals, output
            channels, actuator map and velocities, regimes. ``options`` is a dict of plant options
            from the command line (``{"conditioning": Conditioning, "tensions": "dynamometer"}``).
        baseline: ``fn(description) -> tuple of effect ids`` of the nominal model.
        candidates: ``fn(description) -> tuple of effect ids`` that diagnose may try (the model's
            own effects are skipped).
        channels_doc: one line describing the output channels (for docs and reports).
        simulate: optional free-run comparison ``fn(ds, params) -> dict`` shown by ``compare``.
        simulation_fit: optional simulation-based fit ``fn(ds, start_params, *, objective,
            progress=False) -> SimulationFit`` (``identify --simulation nmse|pearson``).
        section: ``fn(mapping) -> dataclass``: parses and validates the plant's section of the
            description YAML (CONTRACT section 3), one-line errors naming the key path.
        dump_section: optional ``fn(dataclass) -> mapping`` (default: the dataclass fields).
        contract_topics: every topic (name -> type) a recording of the plant holds (CONTRACT
            section 2 plus documented additions), without /clock and /plant_description.
        joint_topic: the JointState topic ``cablelab import`` writes, with ``joints`` its names.
        joints: joint names on ``joint_topic`` (None when they depend on the description).
        capabilities: what the plant's datasets offer to generic effects, e.g.
            ``"joint_actuators"`` (per-joint actuator velocities and efforts: joint friction and
            the like), ``"winch_actuators"`` (CDPR winch motors).
        estimate: optional ``fn(bag, desc, **options) -> Estimate`` for ``cablelab estimate``
            (an object with ``summary() -> dict``, or a dict).
        checked_topics: topics besides ``topics`` whose time base is checked when present.
        check_bag: optional ``fn(bag, desc, options, series) -> list of warnings`` run before
            every fit (:func:`cablelab.bagcheck.check_bag`; ``series``: topic -> decoded series):
            names against the description (one-line errors), physically impossible values.
        options: the plant-specific command-line options it reads, by ``argparse`` dest
            (``("tensions", "pose")`` for the CDPR); a verb refuses such an option given for a
            bag of another plant (one line naming the option and the plants it belongs to).
        package: the Python package of the plant (filled in by :func:`get_plant`).
        remeasure: optional ``fn(ds, shifted) -> Dataset`` used by ``time_delay``
            (:mod:`cablelab.effects.delay`) when the output channels are raw measurements mapped
            through a motion-dependent matrix (CDPR: wrench = W(pose) x measured tensions):
            ``shifted`` has every motion signal at ``t - tau``; the hook puts the raw
            measurement back unshifted and re-forms ``y`` and the signals computed from it
            with the map of the time the measurement belongs to. None: nothing to re-form.
    """

    name: str
    topics: tuple[tuple[str, str], ...]
    dataset: Callable
    baseline: Callable
    candidates: Callable
    channels_doc: str = ""
    simulate: Callable | None = None
    simulation_fit: Callable | None = None
    section: Callable | None = None
    dump_section: Callable | None = None
    contract_topics: Mapping[str, str] = field(default_factory=dict)
    joint_topic: str = ""
    joints: tuple[str, ...] | None = None
    capabilities: frozenset = frozenset()
    estimate: Callable | None = None
    checked_topics: tuple[str, ...] = ()
    check_bag: Callable | None = None
    package: str = ""
    remeasure: Callable | None = None
    options: tuple[str, ...] = ()


def register_plant(plant: Plant) -> Plant:
    """Register a plant (at import of its package). Returns it, for module-level use."""
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


def get_plant(name: str) -> Plant:
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
        from dataclasses import replace

        package = _discovered().get(name) or _REGISTRY[name].dataset.__module__.rsplit(".", 1)[0]
        _REGISTRY[name] = replace(_REGISTRY[name], package=package)
    return _REGISTRY[name]


def plant_module(name: str, module: str):
    """The module ``<plant package>.<module>`` of plant ``name`` (e.g. its ``nodes``)."""
    plant = get_plant(name)
    return importlib.import_module(f"{plant.package}.{module}")


__all__ = ["ENTRY_POINT_GROUP", "Plant", "available_plants", "get_plant", "plant_module",
           "plant_packages", "register_plant"]
