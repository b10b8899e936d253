"""`payload_estimator --plant leg`: adapter in cablelab.plants.leg.nodes (temporary shim, branch leg)."""
from cablelab.plants.leg.nodes import make_node_for


def make_node(args):
    return make_node_for("estimator", args)
