"""``control_loop --plant PLANT``: a plant's hardware (its simulator, or a driver) and its
PD + feedforward law in one process on absolute deadlines, the ros2_control way.

The node is the plant's ``nodes/control_loop.py`` (``make_node()``); see
:mod:`cablelab.ros.control_loop` and docs/nodes.md.
"""
import sys

from cablelab.ros.runner import role_main

main = role_main("control_loop", "control_loop", "Control loop of a cablelab plant: read the hardware "
                 "(simulator or driver), update the PD + feedforward law, write the command, every "
                 "period on absolute deadlines; states, commands and references published for the "
                 "other nodes.")

if __name__ == "__main__":
    sys.exit(main())
