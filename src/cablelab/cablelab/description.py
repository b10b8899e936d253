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

PLANTS = ("cdpr", "crane", "axis", "suspended", "leg")


@dataclass(frozen=True)
class Cable:
    """One cable: exit point A_i (world), anchor point B_i (platform frame), pulley swivel axis."""

    exit_point: np.ndarray
    anchor_point: np.ndarray
    swivel_axis: np.ndarray = field(default_factory=lambda: np.array([0.0, 0.0, 1.0]))


@dataclass(frozen=True)
class CdprDescription:
    """CDPR geometry and drives (001 sec. II). Lengths in m, masses in kg."""

    drum_radius: float
    gear_ratio: float
    cables: tuple[Cable, ...]
    platform_mass: float | None = None
    pulley_radius: float = 0.0  # 0 = pulleys unknown / treated as points (Model I)

    @property
    def exit_points(self) -> np.ndarray:
        """(n, 3) exit points A_i in world."""
        return np.array([c.exit_point for c in self.cables])

    @property
    def anchor_points(self) -> np.ndarray:
        """(n, 3) anchor points B_i in the platform frame."""
        return np.array([c.anchor_point for c in self.cables])

    @property
    def swivel_axes(self) -> np.ndarray:
        """(n, 3) unit swivel axes."""
        return np.array([c.swivel_axis for c in self.cables])


@dataclass(frozen=True)
class Counterbalance:
    mass: float
    distance: float


@dataclass(frozen=True)
class CraneDescription:
    """Boom crane of 002: boom length l_b (m), masses (kg), optional counterbalance."""

    boom_length: float
    payload_mass: float | None = None
    boom_mass: float | None = None
    counterbalance: Counterbalance | None = None


@dataclass(frozen=True)
class AxisDescription:
    """Single drive: prismatic (m, kg, N) or revolute (rad, kg m^2, N m)."""

    joint_type: str
    inertia: float | None = None
    gravity_moment: float = 0.0  # m*c in kg m; load torque m*c*g*sin(q), q = 0 hanging down


@dataclass(frozen=True)
class Description:
    """A validated plant description (CONTRACT section 3)."""

    plant: str
    name: str = ""
    gravity: float = 9.81
    cdpr: CdprDescription | None = None
    crane: CraneDescription | None = None
    axis: AxisDescription | None = None
    extra: dict = field(default_factory=dict)  # sections of plants without a schema yet
    yaml_text: str = ""

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

def _cdpr(obj: Any) -> CdprDescription:
    path = "cdpr"
    obj = _mapping(obj, path)
    _check_keys(obj, path, ("drum_radius", "gear_ratio", "cables"), ("platform_mass", "pulley_radius"))
    cables_raw = obj["cables"]
    if not isinstance(cables_raw, list) or not cables_raw:
        raise _fail("cdpr.cables", "expected a non-empty list of cables")
    cables = []
    for i, c in enumerate(cables_raw):
        cp = f"cdpr.cables[{i}]"
        c = _mapping(c, cp)
        _check_keys(c, cp, ("exit_point", "anchor_point"), ("swivel_axis",))
        axis = _vector(c, "swivel_axis", cp, default=[0.0, 0.0, 1.0])
        norm = float(np.linalg.norm(axis))
        if norm < 1e-9:
            raise _fail(f"{cp}.swivel_axis", "must not be the zero vector")
        cables.append(Cable(_vector(c, "exit_point", cp), _vector(c, "anchor_point", cp), axis / norm))
    return CdprDescription(
        drum_radius=_number(obj, "drum_radius", path, positive=True),
        gear_ratio=_number(obj, "gear_ratio", path, positive=True),
        cables=tuple(cables),
        platform_mass=_number(obj, "platform_mass", path, positive=True),
        pulley_radius=_number(obj, "pulley_radius", path, nonneg=True, default=0.0),
    )


def _crane(obj: Any) -> CraneDescription:
    path = "crane"
    obj = _mapping(obj, path)
    _check_keys(obj, path, ("boom_length",), ("payload_mass", "boom_mass", "counterbalance"))
    cb = None
    if obj.get("counterbalance") is not None:
        cbo = _mapping(obj["counterbalance"], "crane.counterbalance")
        _check_keys(cbo, "crane.counterbalance", ("mass", "distance"), ())
        cb = Counterbalance(_number(cbo, "mass", "crane.counterbalance", nonneg=True),
                            _number(cbo, "distance", "crane.counterbalance", nonneg=True))
    return CraneDescription(
        boom_length=_number(obj, "boom_length", path, positive=True),
        payload_mass=_number(obj, "payload_mass", path, positive=True),
        boom_mass=_number(obj, "boom_mass", path, nonneg=True),
        counterbalance=cb,
    )


def _axis(obj: Any) -> AxisDescription:
    path = "axis"
    obj = _mapping(obj, path)
    _check_keys(obj, path, ("joint_type",), ("inertia", "gravity_moment"))
    jt = obj["joint_type"]
    if jt not in ("revolute", "prismatic"):
        raise _fail("axis.joint_type", f"expected 'revolute' or 'prismatic', got {jt!r}")
    gm = _number(obj, "gravity_moment", path, default=0.0)
    if jt == "prismatic" and gm:
        raise _fail("axis.gravity_moment", "only applies to a revolute joint")
    return AxisDescription(joint_type=jt, inertia=_number(obj, "inertia", path, positive=True),
                           gravity_moment=gm)


_SECTIONS = {"cdpr": _cdpr, "crane": _crane, "axis": _axis}


def parse_description(data: Any, source: str = "description") -> Description:
    """Validate an already-parsed YAML mapping; ``source`` prefixes nothing, it is for messages."""
    data = _mapping(data, source)
    _check_keys(data, "", ("plant",), ("name", "gravity") + PLANTS)
    plant = data["plant"]
    if plant not in PLANTS:
        raise _fail("plant", f"unknown plant {plant!r} (expected one of {', '.join(PLANTS)})")
    if plant in _SECTIONS and plant not in data:
        raise _fail(plant, "missing required key (the section of the plant named by 'plant')")
    name = data.get("name", "")
    if name is None:
        name = ""
    if not isinstance(name, str):
        raise _fail("name", f"expected text, got {name!r}")
    gravity = _number(data, "gravity", "", nonneg=True, default=9.81)
    kwargs: dict[str, Any] = {}
    extra = {}
    for key in PLANTS:
        if key in data and data[key] is not None:
            if key in _SECTIONS:
                kwargs[key] = _SECTIONS[key](data[key])
            else:
                extra[key] = _mapping(data[key], key)
    if "suspended" in extra:  # issue 11: validate (the section stays in extra until the restructure)
        from .plants.suspended.description import parse_section
        parse_section(extra["suspended"])
    return Description(plant=plant, name=name, gravity=gravity, extra=extra, **kwargs)


def load_description(src: str | os.PathLike) -> Description:
    """Load a description from a YAML file path or from YAML text.

    Raises:
        CablelabError: unreadable file, bad YAML, or an invalid key (message names the key path).
    """
    text = str(src)
    origin = "description"
    if "\n" not in text and not text.lstrip().startswith(("plant", "{")):
        if not os.path.exists(text):
            raise CablelabError(f"{text}: description file not found")
        try:
            with open(text, encoding="utf-8") as fh:
                text = fh.read()
        except OSError as exc:
            raise CablelabError(f"{src}: cannot read description ({exc.strerror})") from None
        origin = str(src)
    try:
        data = yaml.safe_load(text)
    except yaml.YAMLError as exc:
        mark = getattr(exc, "problem_mark", None)
        where = f" line {mark.line + 1}" if mark is not None else ""
        raise CablelabError(f"{origin}:{where} bad YAML ({getattr(exc, 'problem', exc)})") from None
    if data is None:
        raise CablelabError(f"{origin}: empty description")
    try:
        desc = parse_description(data, origin)
    except CablelabError as exc:
        if origin != "description":
            raise CablelabError(f"{origin}: {exc}") from None
        raise
    return dataclasses.replace(desc, yaml_text=text)


def _plain(obj: Any) -> Any:
    if isinstance(obj, np.ndarray):
        return [float(x) for x in obj]
    if dataclasses.is_dataclass(obj):
        return {k: _plain(v) for k, v in dataclasses.asdict(obj).items() if v is not None}
    if isinstance(obj, (list, tuple)):
        return [_plain(x) for x in obj]
    if isinstance(obj, dict):
        return {k: _plain(v) for k, v in obj.items()}
    return obj


def description_dict(desc: Description) -> dict:
    """The description as a plain mapping in the YAML schema of CONTRACT section 3."""
    out: dict[str, Any] = {"plant": desc.plant}
    if desc.name:
        out["name"] = desc.name
    out["gravity"] = desc.gravity
    for key in ("cdpr", "crane", "axis"):
        sec = getattr(desc, key)
        if sec is not None:
            d = _plain(dataclasses.asdict(sec))
            d = {k: v for k, v in d.items() if v is not None}
            if key == "cdpr":
                d["cables"] = [{k: _plain(v) for k, v in vars(c).items()} for c in sec.cables]
            out[key] = d
    out.update(desc.extra)
    return out


def dump_description(desc: Description) -> str:
    """YAML text of a description (round-trips through :func:`load_description`)."""
    return yaml.safe_dump(description_dict(desc), sort_keys=False)
