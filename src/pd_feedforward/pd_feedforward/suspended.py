"""``pd_feedforward --plant suspended`` (temporary shim until the plant folder owns its nodes)."""
from cablelab.plants.suspended.nodes import make_node as _make


def make_node(args):
    return _make("controller", args)
