"""``pd_feedforward --plant {cdpr,crane,axis}``: PD + feedforward controller node of a plant.

The plant's adapter is the module ``pd_feedforward.<plant>`` (``make_node(args)``); see
:func:`cablelab.ros.runner.plant_main` and docs/nodes.md.
"""
import sys

from cablelab.ros.runner import plant_main


def main(argv=None) -> int:
    return plant_main("pd_feedforward", argv, "PD + feedforward controller of a cablelab plant: "
                      "follows the plant's reference, publishes effort commands.")


if __name__ == "__main__":
    sys.exit(main())
