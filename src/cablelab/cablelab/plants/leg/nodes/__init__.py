"""The leg's ROS 2 nodes, one module per role (``sim``, ``estimator``, ``controller``), each with
``PARAMETERS`` (from :mod:`.parameters`) and ``make_node()``; run by the node executables
(``cable_sim_node --plant leg``, ...). Topics: :mod:`..topics`."""
from __future__ import annotations

from ....ros import convert

HOP_NAMES = ["height", "phase", "apex_height", "grf"]


def hop_msg(t: float, z: float, zd: float, phase: int, apex_height: float, apex_time: float,
            grf: float):
    """A ``/leg/hop_estimate`` (or ground-truth) message: ``height`` (z, zdot), ``phase``,
    ``apex_height`` (position = last apex z, velocity = its time), ``grf`` (effort)."""
    return convert.joint_state_msg(t, HOP_NAMES, [z, float(phase), apex_height, 0.0],
                                   [zd, 0.0, apex_time, 0.0], [0.0, 0.0, 0.0, grf])
