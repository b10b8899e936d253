"""Plant description: the YAML of CONTRACT section 3, loaded and validated.

``load_description(text_or_path)`` returns a :class:`Description` (plain dataclasses over numpy
arrays, SI units). Unknown keys, missing required keys, wrong types and wrong vector lengths raise
:class:`~cablelab.errors.CablelabError` with a one-line message naming the key path, e.g.
``cdpr.cables[3].anchor_point: expected 3 numbers, got 2``.
"""
from __future__ import annotations

import contextvars
import dataclasses
import os
import re
from dataclasses import dataclass, field
from typing import Any

import numpy as np
import yaml

from .errors import CablelabError
from .fields import check_keys, fail, mapping, number

#: keys of the description's top level besides the plant sections
COMMON_KEYS = ("plant", "name", "gravity")
#: directory of the description file being parsed ("" for YAML text): a plant section's relative
#: file names (``mjcf.model_file``) refer to it
DESCRIPTION_DIR: contextvars.ContextVar[str] = contextvars.ContextVar("description_dir", default="")


@dataclass(frozen=True)
class Description:
    """A validated plant description (CONTRACT section 3).

    ``sections`` maps a plant name to its parsed section (the dataclass its plant's
    ``section`` parser returns; a plain mapping for a plant without a parser). A section is
    also an attribute: ``desc.cdpr`` is ``desc.sections.get("cdpr")`` for every known plant.
    """

    plant: str
    name: str = ""
    gravity: float = 9.81
    sections: dict = field(default_factory=dict)
    yaml_text: str = ""

    def __getattr__(self, key: str):
        if key.startswith("_"):
            raise AttributeError(key)
        from .registry import available_plants

        if key in self.sections or key in available_plants():
            return self.sections.get(key)
        raise AttributeError(f"description has no section or field {key!r}")

    @property
    def section(self):
        """The section of the plant the description is for."""
        return self.sections.get(self.plant)

    def with_section(self, name: str, section) -> "Description":
        """A copy with plant section ``name`` replaced (the YAML text is regenerated)."""
        return dataclasses.replace(self, sections={**self.sections, name: section}, yaml_text="")

    def to_yaml(self) -> str:
        """The description as YAML (the original text when it was loaded from text)."""
        return self.yaml_text or dump_description(self)


# ----------------------------------------------------------------------------- YAML 1.2 reading

class DescriptionLoader(yaml.SafeLoader):
    """PyYAML's safe loader with YAML 1.2 core-schema scalars and no duplicated keys.

    PyYAML implements YAML 1.1, where ``2e3`` (no dot) is text and ``yes``/``no``/``on``/``off``
    are booleans, ``1:30`` is 90 and ``010`` is octal; YAML 1.2 (what other tools write and
    users expect) reads ``2e3`` as the number 2000.0, only ``true``/``false`` as booleans,
    ``010`` as 10. A key given twice in one mapping is an error naming it and both lines (1.1
    loaders keep the last one silently)."""

    yaml_implicit_resolvers: dict = {}

    def construct_mapping(self, node, deep=False):
        seen: dict = {}
        for key_node, _ in node.value:
            key = self.construct_object(key_node, deep=True)
            try:
                first = seen.get(key)
            except TypeError:               # an unhashable key: PyYAML's own error follows
                continue
            if first is not None:
                raise CablelabError(f"line {key_node.start_mark.line + 1}: duplicated key {key!r} "
                                    f"(first given on line {first})")
            seen[key] = key_node.start_mark.line + 1
        return super().construct_mapping(node, deep=deep)

    def construct_yaml_int(self, node):
        text = self.construct_scalar(node)
        return int(text, 0) if text.lstrip("+-").startswith(("0x", "0o")) else int(text, 10)


_INT = r"^(?:[-+]?[0-9]+|0o[0-7]+|0x[0-9a-fA-F]+)$"
_FLOAT = (r"^(?:[-+]?(?:\.[0-9]+|[0-9]+(?:\.[0-9]*)?)(?:[eE][-+]?[0-9]+)?"
          r"|[-+]?\.(?:inf|Inf|INF)|\.(?:nan|NaN|NAN))$")
for _tag, _regexp, _first in (
        ("tag:yaml.org,2002:bool", r"^(?:true|True|TRUE|false|False|FALSE)$", "tTfF"),
        ("tag:yaml.org,2002:int", _INT, "-+0123456789"),
        ("tag:yaml.org,2002:float", _FLOAT, "-+0123456789."),
        ("tag:yaml.org,2002:null", r"^(?:~|null|Null|NULL|)$", ["~", "n", "N", ""])):
    DescriptionLoader.add_implicit_resolver(_tag, re.compile(_regexp), list(_first))
DescriptionLoader.add_constructor("tag:yaml.org,2002:int", DescriptionLoader.construct_yaml_int)


def read_yaml(text: str):
    """Parse YAML text with :class:`DescriptionLoader` (YAML 1.2 numbers, no duplicated keys)."""
    return yaml.load(text, Loader=DescriptionLoader)  # noqa: S506 - a SafeLoader subclass


# ----------------------------------------------------------------------------- plant sections

def parse_description(data: Any, source: str = "description") -> Description:
    """Validate an already-parsed YAML mapping; ``source`` prefixes nothing, it is for messages.

    Each plant section is parsed by its plant's ``parse_section`` (found through
    :mod:`cablelab.registry`); the section of the plant named by ``plant`` is required."""
    from .registry import available_plants, get_plant

    data = mapping(data, source)
    plants = tuple(available_plants())
    check_keys(data, "", ("plant",), COMMON_KEYS[1:] + plants)
    plant = data["plant"]
    if plant not in plants:
        raise fail("plant", f"unknown plant {plant!r} (expected one of {', '.join(plants)})")
    name = data.get("name", "")
    if name is None:
        name = ""
    if not isinstance(name, str):
        raise fail("name", f"expected text, got {name!r}")
    gravity = number(data, "gravity", "", nonneg=True, default=9.81)
    get_plant(plant)
    if data.get(plant) is None:
        raise fail(plant, "missing required key (the section of the plant named by 'plant')")
    sections: dict[str, Any] = {}
    for key in plants:
        if key in data and data[key] is not None:
            sections[key] = get_plant(key).parse_section(data[key])
    return Description(plant=plant, name=name, gravity=gravity, sections=sections)


def load_description(src: str | os.PathLike) -> Description:
    """Load a description from a YAML file path or from YAML text.

    Raises:
        CablelabError: unreadable file, bad YAML, or an invalid key (message names the key path).
    """
    text = str(src)
    origin = "description"
    if "\n" not in text and not text.lstrip().startswith(("plant", "{")):
        from .inputs import DESCRIPTION_MAX_BYTES, check_regular_file

        check_regular_file(text, "description", DESCRIPTION_MAX_BYTES)   # never /dev/zero, a FIFO
        try:
            with open(text, encoding="utf-8") as fh:
                text = fh.read(DESCRIPTION_MAX_BYTES + 1)
        except OSError as exc:
            raise CablelabError(f"{src}: cannot read description ({exc.strerror})") from None
        except UnicodeDecodeError as exc:
            raise CablelabError(f"{src}: not a UTF-8 text file (byte 0x{exc.object[exc.start]:02x} at "
                                f"offset {exc.start}): a description is YAML text") from None
        origin = str(src)
    try:
        data = read_yaml(text)
    except CablelabError as exc:                     # a duplicated key
        raise CablelabError(f"{origin}: {exc}") from None
    except yaml.YAMLError as exc:
        mark = getattr(exc, "problem_mark", None)
        where = f" line {mark.line + 1}" if mark is not None else ""
        problem = " ".join(str(getattr(exc, "problem", exc)).split())    # one line
        raise CablelabError(f"{origin}:{where} bad YAML ({problem})") from None
    if data is None:
        raise CablelabError(f"{origin}: empty description")
    token = DESCRIPTION_DIR.set(os.path.dirname(os.path.abspath(origin)) if origin != "description" else "")
    try:
        desc = parse_description(data, origin)
    except CablelabError as exc:
        if origin != "description":
            raise CablelabError(f"{origin}: {exc}") from None
        raise
    finally:
        DESCRIPTION_DIR.reset(token)
    # a section that read a file it names (``inlines_files``) is published with the file's text
    # in it (a bag carries its own model): the YAML is regenerated from the parsed sections
    inlined = any(getattr(sec, "inlines_files", False) for sec in desc.sections.values())
    return dataclasses.replace(desc, yaml_text="" if inlined else text)


def plain(obj: Any) -> Any:
    """``obj`` with numpy arrays, dataclasses and tuples turned into YAML-ready lists/mappings
    (``None`` fields of dataclasses dropped)."""
    if isinstance(obj, np.ndarray):
        return np.asarray(obj, dtype=float).tolist()      # any shape (e.g. two 3-vectors)
    if dataclasses.is_dataclass(obj):
        return {k: plain(getattr(obj, k)) for k in (f.name for f in dataclasses.fields(obj))
                if getattr(obj, k) is not None}
    if isinstance(obj, (list, tuple)):
        return [plain(x) for x in obj]
    if isinstance(obj, dict):
        return {k: plain(v) for k, v in obj.items()}
    return obj


def description_dict(desc: Description) -> dict:
    """The description as a plain mapping in the YAML schema of CONTRACT section 3."""
    from .registry import get_plant

    out: dict[str, Any] = {"plant": desc.plant}
    if desc.name:
        out["name"] = desc.name
    out["gravity"] = desc.gravity
    for key, sec in desc.sections.items():
        dump = get_plant(key).dump_section if dataclasses.is_dataclass(sec) else None
        out[key] = dump(sec) if dump is not None else plain(sec)
    return out


def dump_description(desc: Description) -> str:
    """YAML text of a description (round-trips through :func:`load_description`)."""
    return yaml.safe_dump(description_dict(desc), sort_keys=False)
