"""``./run demo``: the main job (see README). Filled in as the plants land."""
from __future__ import annotations

import sys


def main(argv: list[str] | None = None) -> int:
    print("cablelab demo: nothing to run yet")
    return 0


if __name__ == "__main__":
    sys.exit(main())
