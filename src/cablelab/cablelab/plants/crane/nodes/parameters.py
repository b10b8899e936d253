"""The ROS parameters of the crane plant's nodes, declared once (the way generate_parameter_library
keeps a node's parameters in a YAML file beside it): :data:`SIM` (``cable_sim_node``),
:data:`ESTIMATOR` (``payload_estimator``) and :data:`CONTROLLER` (``pd_feedforward``), typed
specs (:class:`cablelab.ros.params.Param`) each node declares with descriptors and validates
(``NODE --plant crane --help`` and docs/nodes.md list them)."""
from __future__ import annotations

from .. import topics
from ..control import LIVE_GAINS
from ....ros.params import DESCRIPTION, START_GATE, Param, markers_rate, merge
from ....ros.reference import reference_bag_param

__all__ = ["SIM", "ESTIMATOR", "CONTROLLER"]

#: ``cable_sim_node --plant crane``: the true crane (:func:`..sim.truth_from_parameters`), rate, lock-step
SIM = merge((
    DESCRIPTION,
    Param("slew_inertia", 0.05, "slew inertia the description does not hold", "kg m^2", gt=0.0, le=1e6),
    Param("luff_inertia", 0.02, "luff inertia the description does not hold", "kg m^2", gt=0.0, le=1e6),
    Param("base_tilt", [0.0, 0.0], "true tilt of the base [about x, about y]", "rad", length=(2,),
          ge=-0.5, le=0.5),
    Param("viscous", [0.0, 0.0, 0.0], "true viscous friction [slew, luff, hoist]",
          "N m s/rad, N m s/rad, N s/m", length=(3,), ge=0.0, le=1e6),
    Param("coulomb", [0.0, 0.0, 0.0], "true Coulomb friction [slew, luff, hoist]", "N m, N m, N",
          length=(3,), ge=0.0, le=1e6),
    Param("offset", [0.0, 0.0, 0.0], "true effort sensor offset [slew, luff, hoist]", "N m, N m, N",
          length=(3,), ge=-1e6, le=1e6),
    Param("mocap_noise", 0.0, "standard deviation of the motion-capture positions", "m", ge=0.0, le=10.0),
    Param("mocap_dropout", 0.0, "probability of a motion-capture dropout (NaN pose)", ge=0.0, le=1.0),
    Param("timestep", 0.001, "physics step", "s", ge=1e-5, le=0.01),
    Param("initial", [0.0, 0.5, 0.6], "initial [slew rad, luff rad, hoist rope length m]", length=(3,),
          ge=-10.0, le=100.0),
    Param("rate", 100.0, "publishing rate = command sampling", "Hz", ge=1.0, le=10000.0),
    Param("command_timeout", 0.5, "a command older than this is stale: the drives hold (real time)",
          "s wall", gt=0.0),
    Param("lockstep", True, "once commands flow, advance only when the command answering the last "
          "state arrived"),
    Param("lockstep_timeout", 10.0, "lock-step: without an answer for this long, back to real time "
          "holding the crane", "s wall", gt=0.0),
    markers_rate("/crane/markers: mast, boom, rope, payload"),
), START_GATE)

#: ``payload_estimator --plant crane``: the swing tracker and its pose pairing
ESTIMATOR = (
    Param("velocity_tau", 0.02, "time constant smoothing the swing rates", "s", gt=0.0, le=10.0),
    Param("max_wait", 0.2, "a pose pair waits this long (in stamps) for the slew angle of its "
          "stamp before the latest one is used", "s", ge=0.0, le=10.0),
    Param("pose_timeout", 0.5, "a pose older than this is stale", "s wall", gt=0.0),
    Param("slew_timeout", 0.5, "a slew angle older than this is stale", "s wall", gt=0.0),
)

#: ``pd_feedforward --plant crane``: gains, inertias and the reference (topic, excitation or bag)
CONTROLLER = (
    Param("kp", [float(x) for x in LIVE_GAINS.kp], "proportional gains [slew, luff, hoist]",
          "N m/rad, N m/rad, N/m", length=(3,), ge=0.0, le=1e9),
    Param("kd", [float(x) for x in LIVE_GAINS.kd], "derivative gains [slew, luff, hoist]",
          "N m s/rad, N m s/rad, N s/m", length=(3,), ge=0.0, le=1e9),
    Param("feedforward", True, "reference-acceleration feedforward"),
    Param("slew_inertia", 0.05, "slew inertia the description does not hold", "kg m^2", gt=0.0, le=1e6),
    Param("luff_inertia", 0.02, "luff inertia the description does not hold", "kg m^2", gt=0.0, le=1e6),
    Param("reference_source", "topic", "the reference: /crane/reference (topic) or the built-in "
          "multi-sine excitation, published on /crane/reference too (excitation)",
          choices=("topic", "excitation")),
    Param("excitation_seed", 0, "seed of the built-in multi-sine excitation", ge=0),
    Param("reference_timeout", 0.5, "a reference older than this is stale: the crane is held",
          "s wall", gt=0.0),
    reference_bag_param(topics.REFERENCE),
)
