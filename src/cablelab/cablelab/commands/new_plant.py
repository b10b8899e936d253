"""``cablelab new-plant NAME [-o DIR]``: write the skeleton of a new plant package (the plant
template of docs/architecture.md: registration, plant hooks, description section, dataset,
effects, control law, MuJoCo model, simulator, topics, demo part, nodes, README, data, tests).
The skeleton is a working plant (:mod:`cablelab.plant_template`); it is found through the
``cablelab.plants`` entry point once installed (``pip install -e DIR``)."""
from __future__ import annotations

from pathlib import Path

HELP = "write the skeleton of a new plant package (the plant template, tests included)"
DESCRIPTION = (HELP + ". The package works as written (a torque-driven hinge, its nodes and "
               "tests); replace its law file by file. Never overwrites: DIR must not exist.")


def add_arguments(p) -> None:
    p.add_argument("name", metavar="NAME", help="plant id: a lowercase identifier (also the description section "
                   "and topic prefix /NAME/...)")
    p.add_argument("-o", "--output", type=Path, default=None, metavar="DIR",
                   help="directory to create (default: ./NAME); must not exist")


def run(args) -> int:
    from ..plant_template import write_plant

    out = args.output if args.output is not None else Path(args.name)
    files = write_plant(args.name, out)
    print(f"wrote the plant {args.name!r} to {out}/ ({len(files)} files); next: "
          f"pip install -e {out} && python -m pytest {out}")
    return 0
