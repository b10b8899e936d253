"""The suspended platform's ROS 2 nodes, one module per role (``sim``, ``estimator``,
``controller``), each with ``PARAMETERS`` and ``make_node()``; run by the node executables
(``cable_sim_node --plant suspended``, ...). Topics: :mod:`..topics`."""
from __future__ import annotations

import time

import numpy as np

from ..params import VARIANTS
from ....ros import convert
from ....ros.params import Param

VARIANT = Param("variant", "licas", "which platform: LiCAS or CRANEbot", choices=VARIANTS)


def arm_reference(node, msg, names: list[str]):
    """``(q, qd)`` of a ``/suspended/reference`` message for the arm joints ``names`` (qd zero
    when absent), or None after reporting a wrong message (other names, wrong length, NaN) to the
    node's ``reference`` input."""
    _, got, q, qd, _ = convert.joint_trajectory_point(msg)
    ok = q is not None and got == names and len(q) == len(names) and np.all(np.isfinite(q))
    if not node.inputs.accept("reference", q if ok else None, time.monotonic()) or not ok:
        return None
    return q, (qd if qd is not None and len(qd) == len(q) else np.zeros_like(q))
