"""``model_monitor --plant PLANT``: the live model monitor (any plant of the registry); see
:mod:`cablelab.ros.monitor_node` and docs/nodes.md."""
import sys

from cablelab.ros.monitor_node import main

if __name__ == "__main__":
    sys.exit(main())
