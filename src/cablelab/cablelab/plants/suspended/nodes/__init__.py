"""The suspended platform's ROS 2 nodes, one module per role (``sim``, ``estimator``, ``controller``),
each with ``PARAMETERS`` (from :mod:`.parameters`) and ``make_node()``; run by the node executables
(``cable_sim_node --plant suspended``, ...). Topics: :mod:`..topics`."""
from __future__ import annotations

import numpy as np

from ....ros import convert


def arm_reference(node, msg, names: list[str]):
    """``(q, qd)`` of a ``/suspended/reference`` message for the arm joints ``names`` (qd zero
    when absent), or None after reporting a wrong message (other names, wrong length, NaN) to the
    node's ``reference`` input."""
    ref = convert.reference_point(msg, names)
    ok = ref is not None and len(ref[0]) == len(names) and np.all(np.isfinite(ref[0]))
    return ref[:2] if node.accept("reference", ref[0] if ok else None) and ok else None
