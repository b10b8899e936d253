"""Validators of description fields: what a plant's ``parse_section`` checks its YAML section with.

Each takes the parsed mapping, the key and the key path of the mapping (``cdpr.cables[3]``) and
returns the value in SI or raises :class:`~cablelab.errors.CablelabError` with one line naming
the full key path, e.g. ``cdpr.cables[3].anchor_point: expected 3 numbers, got 2``. Numbers are
YAML 1.2 numbers (``2e3``, ``1.5E-3``, ``.5``: :func:`cablelab.description.load_description`
reads them so); integers are accepted where a number is expected, booleans never.

    from cablelab.fields import check_keys, mapping, number, vector

    def parse_section(obj, path="myplant"):
        obj = mapping(obj, path)
        check_keys(obj, path, required=("mass",), optional=("offset",))
        return MyDescription(mass=number(obj, "mass", path, positive=True),
                             offset=vector(obj, "offset", path, n=3, default=(0, 0, 0)))
"""
from __future__ import annotations

import math
from typing import Any

import numpy as np

from .errors import CablelabError

__all__ = ["fail", "mapping", "check_keys", "number", "positive", "vector", "choice"]


def _join(path: str, key) -> str:
    return f"{path}.{key}" if path else str(key)


def fail(path: str, msg: str) -> CablelabError:
    """The error to raise for the field at ``path`` (``raise fail("axis.inertia", "...")``)."""
    return CablelabError(f"{path}: {msg}")


def mapping(obj: Any, path: str) -> dict:
    """``obj`` itself if it is a mapping (a YAML section), else a one-line error."""
    if not isinstance(obj, dict):
        raise fail(path, f"expected a mapping, got {type(obj).__name__}")
    return obj


def check_keys(obj: dict, path: str, required: tuple[str, ...], optional: tuple[str, ...] = ()) -> None:
    """Every key of ``obj`` is in ``required + optional`` and every required one is there."""
    for key in obj:
        if key not in required and key not in optional:
            raise fail(_join(path, key), f"unknown key (allowed: {', '.join(required + optional)})")
    for key in required:
        if key not in obj:
            raise fail(_join(path, key), "missing required key")


def _is_number(v) -> bool:
    return not isinstance(v, bool) and isinstance(v, (int, float))


def number(obj: dict, key: str, path: str, *, positive: bool = False, nonneg: bool = False,
           default: float | None = None, ge: float | None = None, gt: float | None = None,
           le: float | None = None, lt: float | None = None, unit: str = "") -> float | None:
    """The finite number at ``obj[key]`` (``default`` when absent or null), as float.

    Args:
        positive: must be > 0. nonneg: must be >= 0.
        ge, gt, le, lt: further bounds. unit: named in the message (``"m"``).
    """
    p = _join(path, key)
    if key not in obj or obj[key] is None:
        return default
    v = obj[key]
    u = f" {unit}" if unit else ""
    if not _is_number(v):
        hint = " (a number with a dot or an exponent, e.g. 2000.0 or 2e3)" if isinstance(v, str) else ""
        raise fail(p, f"expected a number, got {v!r}{hint}")
    v = float(v)
    if not math.isfinite(v):
        raise fail(p, f"expected a finite number, got {v}")
    if positive and v <= 0:
        raise fail(p, f"expected a positive number, got {v:g}{u}")
    if nonneg and v < 0:
        raise fail(p, f"expected a number >= 0, got {v:g}{u}")
    for bound, ok, op in ((ge, lambda b: v >= b, ">="), (gt, lambda b: v > b, ">"),
                          (le, lambda b: v <= b, "<="), (lt, lambda b: v < b, "<")):
        if bound is not None and not ok(bound):
            raise fail(p, f"expected a number {op} {bound:g}{u}, got {v:g}{u}")
    return v


def positive(obj: dict, key: str, path: str, default: float | None = None, unit: str = "") -> float | None:
    """:func:`number` > 0."""
    return number(obj, key, path, positive=True, default=default, unit=unit)


def vector(obj: dict, key: str, path: str, n: int = 3, default=None) -> np.ndarray:
    """The ``n`` finite numbers at ``obj[key]`` as an (n,) float array (``default`` when absent;
    required when ``default`` is None)."""
    p = _join(path, key)
    if key not in obj:
        if default is None:
            raise fail(p, "missing required key")
        return np.asarray(default, dtype=float)
    v = obj[key]
    if not isinstance(v, (list, tuple)):
        raise fail(p, f"expected {n} numbers, got {v!r}")
    if len(v) != n:
        raise fail(p, f"expected {n} numbers, got {len(v)}")
    for i, x in enumerate(v):
        if not _is_number(x) or not math.isfinite(float(x)):
            raise fail(f"{p}[{i}]", f"expected a finite number, got {x!r}")
    return np.array(v, dtype=float)


def choice(obj: dict, key: str, path: str, choices: tuple[str, ...], default: str | None = None) -> str:
    """The text at ``obj[key]``, one of ``choices``."""
    p = _join(path, key)
    if key not in obj or obj[key] is None:
        if default is None:
            raise fail(p, "missing required key")
        return default
    v = obj[key]
    if v not in choices:
        raise fail(p, f"expected one of {', '.join(repr(c) for c in choices)}, got {v!r}")
    return v
