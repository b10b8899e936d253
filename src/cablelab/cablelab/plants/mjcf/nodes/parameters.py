"""The ROS parameters of the mjcf plant's nodes, declared once (the way generate_parameter_library
keeps a node's parameters in a YAML file beside it): :data:`SIM` (``cable_sim_node``),
:data:`ESTIMATOR` (``payload_estimator``) and :data:`CONTROLLER` (``pd_feedforward``), typed
specs (:class:`cablelab.ros.params.Param`) each node declares with descriptors and validates
(``NODE --plant mjcf --help`` and docs/nodes.md list them)."""
from __future__ import annotations

from ....ros.params import DESCRIPTION, START_GATE, Param, markers_rate, merge
from ....ros.reference import reference_bag_param
from ..topics import TOPICS

__all__ = ["SIM", "ESTIMATOR", "CONTROLLER"]

#: ``cable_sim_node --plant mjcf``: publishing rate, command timeout and the hidden payload
SIM = merge((
    DESCRIPTION,
    Param("rate", float("nan"), "publishing rate = command sampling (NaN: every physics step of "
          "the model)", "Hz", gt=0.0, le=10000.0, nan=True),
    Param("command_timeout", 0.5, "a command older than this falls back to zero controls (WARN)",
          "s wall", gt=0.0),
    Param("payload_mass", 0.0, "mass the simulated truth carries on mjcf.payload_body, at its "
          "centre of mass (not in the published description: what an estimator must find)", "kg",
          ge=0.0, le=1e6),
    markers_rate("/mjcf/markers: the model's geoms and tendons, tendons coloured by tension"),
), START_GATE)

#: ``payload_estimator --plant mjcf``: the sliding window fitted
ESTIMATOR = (
    DESCRIPTION,
    Param("window", 4.0, "length of the sliding window fitted", "s", gt=0.5, le=3600.0),
    Param("publish_every", 200, "fit and publish every this many joint-state messages", ge=1,
          le=10 ** 9),
)

#: ``pd_feedforward --plant mjcf``: gains and the reference (topic, bag or built-in sine)
CONTROLLER = (
    DESCRIPTION,
    Param("kp", 100.0, "proportional gain of the commanded acceleration", "1/s^2", ge=0.0, le=1e9),
    Param("kd", 20.0, "derivative gain of the commanded acceleration", "1/s", ge=0.0, le=1e9),
    Param("reference_source", "topic", "the reference: the reference topic or a built-in sine "
          "around the first measured position (sine)", choices=("topic", "sine")),
    Param("amplitude", 0.2, "amplitude of the built-in sine", "rad or m", ge=0.0, le=1e3),
    Param("frequency", 0.3, "frequency of the built-in sine", "Hz", gt=0.0, le=1e3),
    Param("reference_timeout", 0.5, "a reference older than this is stale", "s wall", gt=0.0),
    reference_bag_param(TOPICS["reference"][0]),
)
