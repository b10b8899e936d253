"""Effect lists written as text: ``"a,b"`` on the command line or a list in a fleet task."""
from __future__ import annotations

from typing import Sequence

def parse_effect_list(text: str | Sequence[str] | None) -> tuple[str, ...]:
    """``"a,b"`` -> ``("a", "b")`` (blank entries dropped)."""
    if text is None:
        return ()
    if isinstance(text, str):
        text = text.split(",")
    return tuple(s.strip() for s in text if s and s.strip())


__all__ = ["parse_effect_list"]
