"""Write the ROS parameter tables of every node of every plant into docs/nodes.md, from the
specs the nodes declare (``PARAMETERS`` of each node module, :mod:`cablelab.ros.params`).

    ./run python docs/parameter_tables.py          # rewrite the generated section
    ./run python docs/parameter_tables.py --check  # exit 1 if docs/nodes.md is stale

test/core/test_node_parameters.py checks the tables match the specs.
"""
from __future__ import annotations

import sys
from pathlib import Path

NODES_MD = Path(__file__).resolve().parent / "nodes.md"
BEGIN, END = "<!-- generated parameter tables -->", "<!-- end generated parameter tables -->"


def section() -> str:
    from cablelab.registry import available_plants
    from cablelab.ros.params import markdown_table
    from cablelab.ros.runner import ROLES, node_module, parameters_of

    parts = [BEGIN, "",
             "Generated from the nodes' parameter specs by `./run python docs/parameter_tables.py`; "
             "`NODE --plant P --help` prints the same list. Every parameter is read once at start-up "
             "(read-only: `ros2 param set` is refused) and checked before use: an integer is "
             "accepted where a number is expected, anything out of range, of the wrong type or "
             "length stops the node with one line naming the node, the parameter, the value and "
             "what is allowed.", ""]
    for plant in available_plants():
        for package, role in {**ROLES, "control_loop": "control_loop"}.items():
            module = node_module(plant, role)
            if module is None:
                continue
            node = f"{package} --plant {plant}"
            parts += [f"### `{node}`", "", f"<!-- parameters: {node} -->",
                      markdown_table(parameters_of(module)), "<!-- end parameters -->", ""]
    from cablelab.registry import get_plant
    from cablelab.ros.monitor_node import PARAMETERS as MONITOR, plant_parameters

    parts += ["### `model_monitor --plant P` (any plant)", "", "<!-- parameters: model_monitor -->",
              markdown_table(MONITOR), "<!-- end parameters -->", ""]
    for plant in available_plants():       # a plant's own options its dataset takes
        own = plant_parameters(get_plant(plant))
        if own:
            node = f"model_monitor --plant {plant}"
            parts += [f"### `{node}`: the plant's own options, besides the above", "",
                      f"<!-- parameters: {node} -->", markdown_table(own), "<!-- end parameters -->", ""]
    parts.append(END)
    return "\n".join(parts)


def main(argv: list[str]) -> int:
    text = NODES_MD.read_text()
    new_section = section()
    if BEGIN in text:
        head, rest = text.split(BEGIN, 1)
        tail = rest.split(END, 1)[1]
        new = head + new_section + tail
    else:
        new = text.rstrip("\n") + "\n\n## ROS parameters of every node\n\n" + new_section + "\n"
    if "--check" in argv:
        if new != text:
            print(f"{NODES_MD}: parameter tables are stale (run ./run python docs/parameter_tables.py)")
            return 1
        return 0
    NODES_MD.write_text(new)
    return 0


if __name__ == "__main__":
    sys.exit(main(sys.argv[1:]))
