"""``pd_feedforward --plant PLANT``: PD + feedforward controller node of a plant.

The node is the plant's ``nodes/controller.py`` (``make_node()``; any plant of the registry); see
:func:`cablelab.ros.runner.plant_main` and docs/nodes.md.
"""
import sys

from cablelab.ros.runner import role_main

main = role_main("pd_feedforward", "controller", "PD + feedforward controller of a cablelab plant: "
                   "follows the plant's reference, publishes effort commands.")

if __name__ == "__main__":
    sys.exit(main())
