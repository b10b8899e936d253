"""Plant description: the YAML of CONTRACT section 3, loaded and validated.

``load_description(text_or_path)`` returns a :class:`Description` (plain dataclasses over numpy
arrays, SI units). Unknown keys, missing required keys, wrong types and wrong vector lengths raise
:class:`~cablelab.errors.CablelabError` with a one-line message naming the key path, e.g.
``cdpr.cables[3].anchor_point: expected 3 numbers, got 2``.
"""
from __future__ import annotations

import dataclasses
import math
import os
from dataclasses import dataclass, field
from typing import Any

import numpy as np
import yaml

from .errors import CablelabError

#: keys of the description's top level besides the plant sections
COMMON_KEYS = ("plant", "name", "gravity")


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


# ----------------------------------------------------------------------------- validation helpers

def _fail(path: str, msg: str) -> CablelabError:
    return CablelabError(f"{path}: {msg}")


def _mapping(obj: Any, path: str) -> dict:
    if not isinstance(obj, dict):
        raise _fail(path, f"expected a mapping, got {type(obj).__name__}")
    return obj


def _check_keys(obj: dict, path: str, required: tuple[str, ...], optional: tuple[str, ...]) -> None:
    for key in obj:
        if key not in required and key not in optional:
            allowed = ", ".join(required + optional)
            raise _fail(f"{path}.{key}" if path else str(key), f"unknown key (allowed: {allowed})")
    for key in required:
        if key not in obj:
            raise _fail(f"{path}.{key}" if path else key, "missing required key")


def _number(obj: dict, key: str, path: str, *, positive: bool = False, nonneg: bool = False,
            default: float | None = None) -> float | None:
    p = f"{path}.{key}" if path else key
    if key not in obj or obj[key] is None:
        return default
    v = obj[key]
    if isinstance(v, bool) or not isinstance(v, (int, float)):
        raise _fail(p, f"expected a number, got {v!r}")
    v = float(v)
    if not math.isfinite(v):
        raise _fail(p, f"expected a finite number, got {v}")
    if positive and v <= 0:
        raise _fail(p, f"expected a positive number, got {v:g}")
    if nonneg and v < 0:
        raise _fail(p, f"expected a number >= 0, got {v:g}")
    return v


def _vector(obj: dict, key: str, path: str, n: int = 3, default=None) -> np.ndarray:
    p = f"{path}.{key}"
    if key not in obj:
        if default is None:
            raise _fail(p, "missing required key")
        return np.asarray(default, dtype=float)
    v = obj[key]
    if not isinstance(v, (list, tuple)):
        raise _fail(p, f"expected {n} numbers, got {v!r}")
    if len(v) != n:
        raise _fail(p, f"expected {n} numbers, got {len(v)}")
    for i, x in enumerate(v):
        if isinstance(x, bool) or not isinstance(x, (int, float)) or not math.isfinite(float(x)):
            raise _fail(f"{p}[{i}]", f"expected a finite number, got {x!r}")
    return np.array(v, dtype=float)


# ----------------------------------------------------------------------------- plant sections

def parse_description(data: Any, source: str = "description") -> Description:
    """Validate an already-parsed YAML mapping; ``source`` prefixes nothing, it is for messages.

    Each plant section is parsed by its plant's ``section`` function (found through
    :mod:`cablelab.registry`); the section of the plant named by ``plant`` is required."""
    from .registry import available_plants, get_plant

    data = _mapping(data, source)
    plants = tuple(available_plants())
    _check_keys(data, "", ("plant",), COMMON_KEYS[1:] + plants)
    plant = data["plant"]
    if plant not in plants:
        raise _fail("plant", f"unknown plant {plant!r} (expected one of {', '.join(plants)})")
    name = data.get("name", "")
    if name is None:
        name = ""
    if not isinstance(name, str):
        raise _fail("name", f"expected text, got {name!r}")
    gravity = _number(data, "gravity", "", nonneg=True, default=9.81)
    parser = get_plant(plant).section
    if parser is not None and data.get(plant) is None:
        raise _fail(plant, "missing required key (the section of the plant named by 'plant')")
    sections: dict[str, Any] = {}
    for key in plants:
        if key in data and data[key] is not None:
            parse = get_plant(key).section
            sections[key] = parse(data[key]) if parse is not None else _mapping(data[key], key)
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
        origin = str(src)
    try:
        data = yaml.safe_load(text)
    except yaml.YAMLError as exc:
        mark = getattr(exc, "problem_mark", None)
        where = f" line {mark.line + 1}" if mark is not None else ""
        problem = " ".join(str(getattr(exc, "problem", exc)).split())    # one line
        raise CablelabError(f"{origin}:{where} bad YAML ({problem})") from None
    if data is None:
        raise CablelabError(f"{origin}: empty description")
    try:
        desc = parse_description(data, origin)
    except CablelabError as exc:
        if origin != "description":
            raise CablelabError(f"{origin}: {exc}") from None
        raise
    return dataclasses.replace(desc, yaml_text=text)


def plain(obj: Any) -> Any:
    """``obj`` with numpy arrays, dataclasses and tuples turned into YAML-ready lists/mappings
    (``None`` fields of dataclasses dropped)."""
    if isinstance(obj, np.ndarray):
        return [float(x) for x in obj]
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
