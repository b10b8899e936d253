"""``payload_estimator --plant PLANT``: estimator node of a plant.

The node is the plant's ``nodes/estimator.py`` (``make_node()``; any plant of the registry); see
:func:`cablelab.ros.runner.plant_main` and docs/nodes.md.
"""
import sys

from cablelab.ros.runner import role_main

main = role_main("payload_estimator", "estimator", "Live estimator of a cablelab plant (CDPR payload "
                   "mass and CoM, crane swing angles, axis parameters).")

if __name__ == "__main__":
    sys.exit(main())
