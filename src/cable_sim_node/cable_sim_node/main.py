"""``cable_sim_node --plant PLANT``: the MuJoCo simulator node of a plant.

The node is the plant's ``nodes/sim.py`` (``make_node()``; any plant of the registry); see
:func:`cablelab.ros.runner.plant_main` and docs/nodes.md.
"""
import sys

from cablelab.ros.runner import role_main

main = role_main("cable_sim_node", "sim", "MuJoCo simulator of a cablelab plant: publishes "
                   "its joint states, sensors, /clock and /plant_description.")

if __name__ == "__main__":
    sys.exit(main())
