"""The typed plant interface: what a plant package hands :func:`cablelab.registry.register_plant`.

* :class:`PlantInterface`: the members every plant has, with their signatures (a runtime-checkable
  :class:`typing.Protocol`; :func:`missing_members` names what an object lacks).
* :class:`Plant`: the frozen record that implements it (a plant fills in its hooks, the optional
  ones default to None).
* :class:`DatasetOptions`: what a plant's ``dataset`` and ``check_bag`` are given (conditioning,
  the velocities to derive, the plant's own typed options).
* :func:`option`: declares a field of a plant's own options dataclass as a command-line option of
  the verbs that read its bags (CDPR: ``--tensions``, ``--pose``).
"""
from __future__ import annotations

import dataclasses
from dataclasses import dataclass, field
from typing import TYPE_CHECKING, Any, Callable, Mapping, Protocol, runtime_checkable

from .errors import CablelabError

if TYPE_CHECKING:
    from .conditioning import Conditioning
    from .dataset import Dataset

#: what a plant's hooks receive: a :class:`cablelab.bags.Bag` and a
#: :class:`cablelab.description.Description` (named here, not imported: the registry that checks
#: plants against this interface sits below the bag reader and the description loader)
Bag = Any
Description = Any

#: the verbs that read a recorded run of a plant and build its dataset
WORKBENCH_VERBS = ("compare", "diagnose", "identify", "report", "estimate", "excite")


@dataclass(frozen=True)
class CliOption:
    """A plant option as the command line offers it (see :func:`option`).

    Attributes:
        flag: the option as typed (``--tensions``); help: one line for ``--help`` (the verb adds
        "<plant> only:"); choices: the accepted values (None: any text); verbs: the verbs that
        offer it.
    """

    flag: str
    help: str
    choices: tuple[str, ...] | None = None
    verbs: tuple[str, ...] = WORKBENCH_VERBS


def option(default: Any, *, help: str, choices: tuple[str, ...] | None = None,
           verbs: tuple[str, ...] = WORKBENCH_VERBS, flag: str | None = None) -> Any:
    """A field of a plant's options dataclass that is also a command-line option.

    ``flag`` defaults to ``--<field name>`` with ``_`` as ``-``. Given on the command line for a
    bag of another plant, the option is refused with one line naming the plants it belongs to.

    Example (the CDPR)::

        @dataclass(frozen=True)
        class CdprOptions:
            tensions: str = option("dynamometer", choices=("dynamometer", "motor", "both"),
                                   help="cable tensions from ...")
    """
    return field(default=default, metadata={"cli": CliOption(flag or "", help, choices, verbs)})


def cli_options(options_type: type | None) -> list[tuple[str, CliOption]]:
    """``(dest, CliOption)`` of every command-line field of a plant's options dataclass."""
    if options_type is None:
        return []
    out = []
    for f in dataclasses.fields(options_type):
        spec = f.metadata.get("cli")
        if spec is not None:
            flag = spec.flag or "--" + f.name.replace("_", "-")
            out.append((f.name, dataclasses.replace(spec, flag=flag)))
    return out


def _default_conditioning() -> "Conditioning":
    from .conditioning import Conditioning   # scipy.signal: imported when a dataset is built

    return Conditioning()


@dataclass(frozen=True)
class DatasetOptions:
    """What a plant's ``dataset`` (and ``check_bag``) is given besides the bag and description.

    Attributes:
        conditioning: filtering, border, decimation of the signals (:class:`Conditioning`).
        derived_velocity: topic -> joint names whose measured velocity contradicts the position
            (:func:`cablelab.bagcheck.check_bag`): the dataset derives those velocities instead.
        plant: the plant's own options, an instance of its ``Plant.options_type`` (None: the
            plant has none, or its defaults).
    """

    conditioning: "Conditioning" = field(default_factory=_default_conditioning)
    derived_velocity: Mapping[str, tuple[str, ...]] = field(default_factory=dict)
    plant: Any = None

    def plant_options(self, options_type: type):
        """The plant's own options (``options_type()`` defaults when none were given)."""
        return self.plant if isinstance(self.plant, options_type) else options_type()

    @classmethod
    def build(cls, plant: "PlantInterface", given: "DatasetOptions | Mapping[str, Any] | None" = None,
              ) -> "DatasetOptions":
        """Options for ``plant`` from a :class:`DatasetOptions` (returned as is) or a mapping
        (``{"conditioning": ..., "derived_velocity": ..., <plant option>: value}``, e.g.
        ``{"tensions": "motor"}`` for the CDPR). Plant options of another plant and unknown keys
        are refused with one line naming them; None values mean "not given".

        Raises:
            CablelabError: a key that is neither a common option nor one of the plant's.
        """
        if isinstance(given, DatasetOptions):
            return given
        given = {k: v for k, v in dict(given or {}).items() if v is not None}
        common = {k: given.pop(k) for k in ("conditioning", "derived_velocity") if k in given}
        own = {f.name for f in dataclasses.fields(plant.options_type)} if plant.options_type else set()
        unknown = sorted(set(given) - own)
        if unknown:
            raise CablelabError(f"option {', '.join(unknown)}: not an option of plant {plant.name} "
                                f"(its options: {', '.join(sorted(own)) or 'none'})")
        plant_opts = plant.options_type(**given) if plant.options_type else None
        return cls(plant=plant_opts, **common)


# ----------------------------------------------------------------------------- hook signatures
DatasetHook = Callable[["Bag", "Description", DatasetOptions], "Dataset"]
EffectsHook = Callable[["Description | None"], tuple[str, ...]]
ParseSectionHook = Callable[[Mapping[str, Any]], Any]
DumpSectionHook = Callable[[Any], Mapping[str, Any]]
SimulateHook = Callable[["Dataset", Mapping[str, float]], dict]
SimulationFitHook = Callable[..., Any]
EstimateHook = Callable[..., Any]   # (bag, desc, options: DatasetOptions, *, effects, out)
CheckBagHook = Callable[["Bag", "Description", DatasetOptions, Mapping[str, Any]], list]
RemeasureHook = Callable[["Dataset", "Dataset"], "Dataset"]
MarkersHook = Callable[["Bag", "Description"], Any]
TopicNamesHook = Callable[["Description | None"], Mapping[str, list]]


@runtime_checkable
class PlantInterface(Protocol):
    """What the workbench, the description loader, the recorder and the nodes ask of a plant.

    Every member must exist; the optional hooks (:data:`OPTIONAL_HOOKS`) may be None.

    Attributes:
        name: plant id (``axis``, ``crane``, ``cdpr``, ...) = ``description.plant`` = the name of
            its description section.
        topics: ``(topic, type)`` pairs a bag must hold for the workbench (checked first).
        contract_topics: every topic (name -> type) a recording of the plant holds (CONTRACT
            section 2 plus documented additions), without /clock and /plant_description.
        checked_topics: topics besides ``topics`` whose time base is checked when present.
        joint_topic: the JointState topic ``cablelab import`` writes, with ``joints`` its names.
        joints: joint names on ``joint_topic`` (None when they depend on the description).
        channels: the output channel names of the plant's datasets (``Dataset.channels`` with the
            default options), for layouts (:mod:`cablelab.layouts`).
        capabilities: what the plant's datasets offer to generic effects, e.g.
            ``"joint_actuators"`` (per-joint actuator velocities and efforts), ``"winch_actuators"``.
        options_type: the dataclass of the plant's own options (:class:`DatasetOptions`.plant),
            its command-line fields declared with :func:`option`; None: no options.
        package: the Python package of the plant (filled in by :func:`cablelab.registry.get_plant`).
    """

    name: str
    topics: tuple[tuple[str, str], ...]
    contract_topics: Mapping[str, str]
    checked_topics: tuple[str, ...]
    joint_topic: str
    joints: tuple[str, ...] | None
    channels: tuple[str, ...]
    capabilities: frozenset
    options_type: type | None
    package: str

    def dataset(self, bag: "Bag", description: "Description", options: DatasetOptions) -> "Dataset":
        """Conditioned signals, output channels, actuator map and velocities, regimes of a bag.

        Raises:
            CablelabError: a topic, joint or value the dataset needs is missing (one line naming it).
        """

    def baseline(self, description: "Description | None") -> tuple[str, ...]:
        """Effect ids of the nominal model."""

    def candidates(self, description: "Description | None") -> tuple[str, ...]:
        """Effect ids a diagnosis may try (the model's own effects are skipped)."""

    def parse_section(self, section: Mapping[str, Any]) -> Any:
        """Parse and validate the plant's section of the description YAML (CONTRACT section 3)
        into a dataclass; one-line errors naming the key path (:mod:`cablelab.fields`)."""

    # optional hooks (None when the plant has none)
    dump_section: DumpSectionHook | None
    """``fn(section) -> mapping`` (None: the dataclass fields)."""
    simulate: SimulateHook | None
    """Free-run comparison ``fn(ds, params) -> dict`` shown by ``compare``."""
    simulation_fit: SimulationFitHook | None
    """``fn(ds, start_params, *, objective, progress=False) -> SimulationFit`` for
    ``identify --simulation nmse|pearson``."""
    estimate: EstimateHook | None
    """``fn(bag, desc, options, *, effects=(), out=None) -> Estimate`` for ``cablelab estimate``
    (``options``: the :class:`DatasetOptions` with the plant's own options; ``effects``: effect
    ids added to the nominal model; ``out``: a bag path to write the per-sample estimates to).
    Returns an object with ``summary() -> dict``, or a dict."""
    check_bag: CheckBagHook | None
    """``fn(bag, desc, options, series) -> list of warnings`` run before every fit
    (``series``: topic -> decoded series): names against the description, impossible values."""
    remeasure: RemeasureHook | None
    """``fn(ds, shifted) -> Dataset`` used by ``time_delay`` when the output channels are raw
    measurements mapped through a motion-dependent matrix (CDPR: W(pose) x tensions)."""
    markers: MarkersHook | None
    """``fn(bag, description) -> (t, frames) | None``: the machine in 3D along a recording."""
    topic_names: TopicNamesHook | None
    """``fn(description or None) -> {topic: element names}`` of the JointState topics whose
    names the contract fixes."""


#: the methods every plant must have (callable, never None)
REQUIRED_METHODS = ("dataset", "baseline", "candidates", "parse_section")
#: the attributes every plant must have
REQUIRED_ATTRIBUTES = ("name", "topics", "contract_topics", "checked_topics", "joint_topic", "joints",
                       "channels", "capabilities", "options_type", "package")
#: hooks every plant must have, callable or None
OPTIONAL_HOOKS = ("dump_section", "simulate", "simulation_fit", "estimate", "check_bag", "remeasure",
                  "markers", "topic_names")


def missing_members(plant: Any) -> list[str]:
    """What ``plant`` lacks of :class:`PlantInterface`, as ``"method dataset"``, ``"attribute
    topics"`` or ``"hook simulate (callable or None)"`` (empty: it satisfies the interface)."""
    out = [f"method {m}" for m in REQUIRED_METHODS if not callable(getattr(plant, m, None))]
    out += [f"attribute {a}" for a in REQUIRED_ATTRIBUTES if not hasattr(plant, a)]
    out += [f"hook {h} (callable or None)" for h in OPTIONAL_HOOKS
            if not hasattr(plant, h) or not (getattr(plant, h) is None or callable(getattr(plant, h)))]
    if hasattr(plant, "name") and not (isinstance(plant.name, str) and plant.name):
        out.append("attribute name (a non-empty text)")
    opt = getattr(plant, "options_type", None)
    if opt is not None and not (isinstance(opt, type) and dataclasses.is_dataclass(opt)):
        out.append("attribute options_type (a dataclass or None)")
    return out


@dataclass(frozen=True)
class Plant:
    """A plant's record for the registry: the :class:`PlantInterface` members as fields (the
    required ones first; every optional hook defaults to None)."""

    name: str
    topics: tuple[tuple[str, str], ...]
    dataset: DatasetHook
    baseline: EffectsHook
    candidates: EffectsHook
    parse_section: ParseSectionHook
    dump_section: DumpSectionHook | None = None
    simulate: SimulateHook | None = None
    simulation_fit: SimulationFitHook | None = None
    contract_topics: Mapping[str, str] = field(default_factory=dict)
    joint_topic: str = ""
    joints: tuple[str, ...] | None = None
    capabilities: frozenset = frozenset()
    estimate: EstimateHook | None = None
    checked_topics: tuple[str, ...] = ()
    check_bag: CheckBagHook | None = None
    package: str = ""
    remeasure: RemeasureHook | None = None
    markers: MarkersHook | None = None
    channels: tuple[str, ...] = ()
    topic_names: TopicNamesHook | None = None
    options_type: type | None = None


__all__ = ["CliOption", "DatasetOptions", "OPTIONAL_HOOKS", "Plant", "PlantInterface",
           "REQUIRED_ATTRIBUTES", "REQUIRED_METHODS", "WORKBENCH_VERBS", "cli_options",
           "missing_members", "option"]
