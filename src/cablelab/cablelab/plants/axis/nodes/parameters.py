"""The ROS parameters of the axis plant's nodes, declared once (the way generate_parameter_library
keeps a node's parameters in a YAML file beside it): :data:`SIM` (``cable_sim_node``),
:data:`ESTIMATOR` (``payload_estimator``) and :data:`CONTROLLER` (``pd_feedforward``), typed
specs (:class:`cablelab.ros.params.Param`) each node declares with descriptors and validates
(``NODE --plant axis --help`` and docs/nodes.md list them)."""
from __future__ import annotations

from .. import topics
from ....ros.params import DESCRIPTION, START_GATE, Param, markers_rate, merge
from ....ros.reference import reference_bag_param

__all__ = ["SIM", "ESTIMATOR", "CONTROLLER"]

#: ``cable_sim_node --plant axis``: the true axis, publishing rate, lock-step
SIM = merge((
    DESCRIPTION,
    Param("inertia", float("nan"), "true inertia M (NaN = the description's axis.inertia, else 2)",
          "kg or kg m^2", gt=0.0, le=1e6, nan=True),
    Param("viscous", 5.0, "true viscous friction Fv", "N s/m or N m s/rad", ge=0.0, le=1e6),
    Param("coulomb", 1.0, "true Coulomb friction Fc", "N or N m", ge=0.0, le=1e6),
    Param("offset", 0.0, "bias added to the reported effort", "N or N m", ge=-1e6, le=1e6),
    Param("timestep", 0.001, "physics step", "s", ge=1e-5, le=0.01),
    Param("rate", 200.0, "publishing rate = command sampling", "Hz", ge=1.0, le=10000.0),
    Param("command_timeout", 0.5, "a command older than this falls back to 0 (WARN)", "s wall", gt=0.0),
    Param("lockstep", False, "advance one period only once the command answering the last state "
          "arrived"),
    Param("lockstep_resend", 0.25, "lock-step: the state is republished this often while waiting",
          "s wall", gt=0.0, le=60.0),
    markers_rate("/axis/markers: carriage on its rail or link and load"),
), START_GATE)

#: ``payload_estimator --plant axis``: the recursive least squares
ESTIMATOR = (
    Param("forgetting", 1.0, "forgetting factor lambda of the recursive least squares (1 = none)",
          gt=0.0, le=1.0),
    Param("publish_every", 20, "publish the estimate every this many samples", ge=1, le=10 ** 9),
    Param("stiction_velocity", 1e-3, "|qd| below which sign(qd) counts as 0", "m/s or rad/s",
          ge=0.0, le=1e3),
)

#: ``pd_feedforward --plant axis``: gains and the reference (topic, built-in sine or bag)
CONTROLLER = (
    Param("kp", 400.0, "proportional gain", "N/m or N m/rad", ge=0.0, le=1e9),
    Param("kd", 40.0, "derivative gain", "N s/m or N m s/rad", ge=0.0, le=1e9),
    Param("inertia", float("nan"), "feedforward inertia M_ff (NaN = the description's axis.inertia "
          "from /plant_description, else 0)", "kg or kg m^2", ge=0.0, le=1e6, nan=True),
    Param("reference_source", "topic", "the reference: /axis/reference (topic) or a built-in sine "
          "evaluated at the measurement stamp and published on /axis/reference (sine)",
          choices=("topic", "sine")),
    Param("amplitude", 0.2, "amplitude of the built-in sine", "m or rad", ge=0.0, le=1e3),
    Param("frequency", 0.5, "frequency of the built-in sine", "Hz", gt=0.0, le=1e3),
    Param("offset", 0.0, "offset of the built-in sine", "m or rad", ge=-1e3, le=1e3),
    Param("reference_timeout", 0.5, "a reference older than this is stale", "s wall", gt=0.0),
    reference_bag_param(topics.REFERENCE),
)
