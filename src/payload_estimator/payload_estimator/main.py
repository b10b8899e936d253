"""``payload_estimator --plant {cdpr,crane,axis}``: estimator node of a plant.

The plant's adapter is the module ``payload_estimator.<plant>`` (``make_node(args)``); see
:func:`cablelab.ros.runner.plant_main` and docs/nodes.md.
"""
import sys

from cablelab.ros.runner import plant_main


def main(argv=None) -> int:
    return plant_main("payload_estimator", argv, "Live estimator of a cablelab plant (CDPR payload "
                      "mass and CoM, crane swing angles, axis parameters).")


if __name__ == "__main__":
    sys.exit(main())
