"""``cable_sim_node --plant {cdpr,crane,axis}``: the MuJoCo simulator node of a plant.

The plant's adapter is the module ``cable_sim_node.<plant>`` (``make_node(args)``); see
:func:`cablelab.ros.runner.plant_main` and docs/nodes.md.
"""
import sys

from cablelab.ros.runner import plant_main


def main(argv=None) -> int:
    return plant_main("cable_sim_node", argv, "MuJoCo simulator of a cablelab plant: publishes "
                      "its joint states, sensors, /clock and /plant_description.")


if __name__ == "__main__":
    sys.exit(main())
