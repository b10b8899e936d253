"""Numeric command-line options: one parser for all of them (``type=number(...)``).

Every numeric option of every verb is read by :func:`number`: the text must be a finite number
(integer spellings and ``1e3`` accepted where a number is expected; an integer option accepts
``5`` and ``5.0``, not ``5.5``) inside the option's range, else argparse prints one line,
``cablelab VERB: error: argument --cutoff: expected a number > 0 [Hz], got '-1'``, exit 2.
"""
from __future__ import annotations

import argparse
import math


def describe(*, gt=None, ge=None, lt=None, le=None, integer: bool = False, unit: str = "") -> str:
    """``a number > 0 [Hz]``, ``an integer >= 1``, ``a number in (0, 1)``."""
    noun = "an integer" if integer else "a number"
    lo = "(" if gt is not None else "[" if ge is not None else ""
    hi = ")" if lt is not None else "]" if le is not None else ""
    a = gt if gt is not None else ge
    b = lt if lt is not None else le
    if lo and hi:
        text = f"{noun} in {lo}{a:g}, {b:g}{hi}"
    elif lo:
        text = f"{noun} {'>' if gt is not None else '>='} {a:g}"
    elif hi:
        text = f"{noun} {'<' if lt is not None else '<='} {b:g}"
    else:
        text = noun
    return text + (f" [{unit}]" if unit else "")


def check_number(value: float, *, gt=None, ge=None, lt=None, le=None, integer: bool = False) -> bool:
    """Whether ``value`` is finite (an integer if ``integer``) and inside the bounds."""
    if isinstance(value, bool) or not isinstance(value, (int, float)) or not math.isfinite(value):
        return False
    if integer and float(value) != int(value):
        return False
    return ((gt is None or value > gt) and (ge is None or value >= ge)
            and (lt is None or value < lt) and (le is None or value <= le))


def number(*, gt=None, ge=None, lt=None, le=None, integer: bool = False, unit: str = ""):
    """An argparse ``type=`` for a finite number (or integer) inside the given bounds."""
    bounds = dict(gt=gt, ge=ge, lt=lt, le=le, integer=integer)
    expected = describe(unit=unit, **bounds)

    def parse(text: str):
        try:
            value = float(str(text).strip().replace("_", "x"))   # (no 1_000: a typo, not a number)
        except ValueError:
            value = math.nan
        if not check_number(value, **bounds):
            raise argparse.ArgumentTypeError(f"expected {expected}, got {text!r}")
        return int(value) if integer else value

    parse.__name__ = "integer" if integer else "number"   # (argparse names the type in messages)
    return parse


__all__ = ["number", "check_number", "describe"]
