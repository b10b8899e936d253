"""The ROS parameters of the leg's nodes, declared once (the way generate_parameter_library keeps
a node's parameters in a YAML file beside it): :data:`SIM` (``cable_sim_node``),
:data:`ESTIMATOR` (``payload_estimator``) and :data:`CONTROLLER` (``pd_feedforward``), typed
specs (:class:`cablelab.ros.params.Param`) each node declares with descriptors and validates
(``NODE --plant leg --help`` and docs/nodes.md list them)."""
from __future__ import annotations

from .. import topics
from ....ros.params import START_GATE, Param, markers_rate, merge
from ....ros.reference import reference_bag_param

__all__ = ["SIM", "ESTIMATOR", "CONTROLLER", "DESCRIPTION"]

#: every leg node's ``description`` (its default is the package's)
DESCRIPTION = Param("description", "", "plant description: YAML file or text (empty = the "
                    "package's data/leg.yaml)")

#: ``cable_sim_node --plant leg``: the true leg, start height, rate
SIM = merge((
    DESCRIPTION,
    Param("mass_scale", 1.0, "true mass / the description's mass", gt=0.0, le=100.0),
    Param("preload", float("nan"), "true spring preload F_0 (NaN = the description's)", "N",
          ge=-1e5, le=1e5, nan=True),
    Param("z0_offset", 0.03, "start height above touch-down height z_td", "m", ge=0.0, le=10.0),
    Param("rate", 1000.0, "simulation and publishing rate", "Hz", ge=1.0, le=100000.0),
    Param("command_timeout", 0.5, "a torque command older than this means zero torque",
          "s wall", gt=0.0),
    Param("lockstep", False, "time starts with the torque answering the start state, then advance "
          "only when the torque answering the last state arrived"),
    Param("lockstep_timeout", 10.0, "lock-step: without an answer for this long, back to real time",
          "s wall", gt=0.0),
    Param("lockstep_resend", 0.25, "lock-step: the start state is resent this often until its answer "
          "arrives", "s wall", gt=0.0, le=60.0),
    markers_rate(f"{topics.MARKERS}: body, links, spring coloured by its force, foot"),
), START_GATE)

#: ``payload_estimator --plant leg``: the hop estimator's phase detection
ESTIMATOR = (
    DESCRIPTION,
    Param("h", 0.5e-3, "height hysteresis of the phase detection", "m", ge=0.0, le=1.0),
    Param("f_on", 1.0, "ground reaction force above which stance starts without a contact switch",
          "N", ge=0.0, le=1e5),
)

#: ``pd_feedforward --plant leg``: the apex-height controller and its reference
CONTROLLER = (
    DESCRIPTION,
    Param("h_des", 0.016, "desired apex height above z_td until a /leg/reference arrives", "m",
          ge=0.0, le=10.0),
    Param("T", 1.0, "initial stance torque", "N m", ge=0.0, le=1e4),
    Param("P", 0.30, "stance torque duration", "s", gt=0.0, le=10.0),
    Param("k_i", 10.0, "integral gain on the apex-height error", "N m/m", ge=0.0, le=1e6),
    Param("k_ff", 0.5, "feedforward fraction of the model-based Newton step", ge=0.0, le=10.0),
    Param("T_max", 4.0, "largest stance torque", "N m", gt=0.0, le=1e4),
    Param("mode", "apex", "apex-height control or a constant open-loop torque",
          choices=("apex", "open_loop")),
    reference_bag_param(topics.REFERENCE, "the topic"),
)
