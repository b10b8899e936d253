"""The ROS parameters of the CDPR's nodes, declared once (the way generate_parameter_library keeps
a node's parameters in a YAML file beside it): :data:`SIM` (``cable_sim_node``), :data:`ESTIMATOR`
(``payload_estimator``) and :data:`CONTROLLER` (``pd_feedforward``), typed specs
(:class:`cablelab.ros.params.Param`) each node declares with descriptors and validates
(``NODE --plant cdpr --help`` and docs/nodes.md list them)."""
from __future__ import annotations

from ....ros.params import DESCRIPTION, START_GATE, Param, executor_params, markers_rate, merge
from ..control import PdffConfig

__all__ = ["SIM", "ESTIMATOR", "CONTROLLER"]

#: ``cable_sim_node --plant cdpr``: the simulated CAROCA's truth, stepping and outputs
SIM = merge((
    DESCRIPTION,
    Param("payload_mass", 0.0, "payload carried by the platform (truth)", "kg", ge=0.0, le=1e5),
    Param("payload_com", [0.15, 0.0, -0.6], "payload centre of mass [x, y, z] in the platform frame "
          "(truth)", "m", length=(3,), ge=-100.0, le=100.0),
    Param("pulleys", True, "simulate the real pulleys (false: cables leave from fixed exit points)"),
    Param("winch_coulomb", 0.3, "Coulomb friction of each winch (truth)", "N m", ge=0.0, le=1e3),
    Param("winch_viscous", 0.002, "viscous friction of each winch (truth)", "N m s/rad", ge=0.0, le=1e3),
    Param("motor_inertia", 2e-4, "rotor inertia of each winch motor (truth)", "kg m^2", gt=0.0, le=10.0),
    Param("tension_noise", 5.0, "standard deviation of the dynamometer noise", "N", ge=0.0, le=1e5),
    Param("tension_bias", [0.0], "dynamometer bias: one value for all cables or one per cable", "N",
          ge=-1e5, le=1e5),
    Param("torque_noise", 0.02, "standard deviation of the motor-torque (current) noise", "N m",
          ge=0.0, le=1e4),
    Param("pose_noise", 0.0, "standard deviation of the measured platform position", "m", ge=0.0, le=10.0),
    Param("timestep", 0.0, "physics step (0 = min(2 ms, 1/rate); else at least 10 us)", "s",
          ge=0.0, le=0.01),
    Param("rate", 100.0, "publishing rate of the state = command sampling", "Hz", ge=1.0, le=10000.0),
    Param("real_time", True, "step at rate Hz of wall time (false: as fast as possible in lock-step "
          "with the controller)"),
    Param("publish_reference", True, "publish /cdpr/reference, the pick-and-place s-curve of 001 "
          "sec. II-C (false: another node publishes it)"),
    Param("reference_lead", -1.0, "time the published reference runs ahead of the state (negative "
          "= 50 ms in real time (at least two periods), 0 in lock-step)", "s", ge=-1.0, le=1.0),
    Param("publish_pose", True, "publish the measured pose /cdpr/platform_pose"),
    Param("trajectory_speed", 1.0, "time scale of the s-curve (2 = twice as fast)", gt=0.0, le=100.0),
    Param("settle", 1.0, "time held at A before the trajectory starts", "s", ge=0.0, le=3600.0),
    Param("duration", 0.0, "simulated time after which the node exits (0 = run until stopped)", "s",
          ge=0.0),
    Param("command_timeout", 0.5, "a command older than this is stale and the winch brakes hold "
          "(real time)", "s wall", gt=0.0),
    Param("lockstep_timeout", 10.0, "lock-step: the step goes ahead (brakes holding) after this long "
          "without the answering command", "s wall", gt=0.0),
    Param("extras_every", 1, "publish /clock, the measured pose and the ground truth every k-th step "
          "(lighter at 1 kHz)", ge=1, le=1000000),
    Param("mass_change", 0.0, "mass put on the platform at its centre of mass at sim time "
          "mass_change_time (a payload change while running, e.g. to test a model monitor; the "
          "ground truth follows)", "kg", ge=-1e5, le=1e5),
    Param("mass_change_time", -1.0, "sim time of the mass change (negative = never)", "s", le=1e9),
    markers_rate("/cdpr/markers: cables coloured by tension, platform, exit points"),
    Param("seed", 0, "seed of the noise generator", ge=0),
), START_GATE, executor_params(True))

#: ``payload_estimator --plant cdpr``: sources and model of the live payload estimate
ESTIMATOR = merge((
    Param("description", "", "plant description: YAML file or text (empty = the first valid "
          "/plant_description)"),
    Param("model", "II", "dynamic model: II (with the platform's inertia terms, 001 eq. 13) or I",
          choices=("II", "I")),
    Param("tensions", "dynamometer", "tension source: the dynamometers (/cdpr/cable_tensions) or "
          "the motor torques, friction compensated (/cdpr/joint_states)",
          choices=("dynamometer", "motor")),
    Param("pose", "desired", "pose of the wrench matrix: the reference (desired, 001's real-time "
          "choice) or /cdpr/platform_pose (measured)", choices=("desired", "measured")),
    Param("platform_inertia", False, "include the platform's own inertia terms"),
    Param("coulomb", 0.0, "Coulomb friction compensation of the motor torques", "N m", ge=0.0, le=1e3),
    Param("viscous", 0.0, "viscous friction compensation of the motor torques", "N m s/rad",
          ge=0.0, le=1e3),
    Param("pulley_radius", 0.0, "pulley radius of the model (0 = the description's)", "m",
          ge=0.0, le=10.0),
    Param("stale_after", 0.5, "largest stamp difference between a tension sample and its pose", "s",
          gt=0.0),
    Param("input_timeout", 0.5, "an input older than this is stale", "s wall", gt=0.0),
    Param("poll_period", 0.0, "0: every input sample gives one estimate; > 0: batch mode, the newest "
          "tension sample estimated every poll_period s (a 1/poll_period Hz estimator on the 1 kHz "
          "stream)", "s", ge=0.0, le=0.1),
), executor_params(True))

_PDFF = PdffConfig()     # the law's default gains

#: ``pd_feedforward --plant cdpr``: the PDFF law and how it waits for its inputs
CONTROLLER = merge((
    Param("description", "", "plant description: YAML file or text (empty = the first valid "
          "/plant_description)"),
    Param("feedforward", True, "mass feedforward of 001 eq. 14 with the live payload estimate "
          "(PDFF; false: PD)"),
    Param("nominal_mass", 0.0, "mass used without a valid estimate (0 = the description's "
          "platform_mass)", "kg", ge=0.0, le=1e5),
    Param("kp", _PDFF.kp, "proportional gain on the motor angles", "N m/rad", ge=0.0, le=1e4),
    Param("kd", _PDFF.kd, "derivative gain on the motor rates", "N m s/rad", ge=0.0, le=1e3),
    Param("coulomb", 0.3, "Coulomb friction compensation F_c (001 eq. 15)", "N m", ge=0.0, le=1e3),
    Param("viscous", 0.002, "viscous friction compensation F_v (001 eq. 15)", "N m s/rad", ge=0.0, le=1e3),
    Param("min_tension", _PDFF.min_tension, "floor on the commanded tensions (cables stay taut)", "N",
          ge=0.0, le=1e6),
    Param("preload", _PDFF.preload, "uniform tension the feedforward distribution stays nearest to", "N",
          ge=0.0, le=1e6),
    Param("max_torque", _PDFF.max_torque, "saturation of the motor torques", "N m", gt=0.0, le=1e5),
    Param("model", "II", "dynamic model of the feedforward: II (with the platform's inertia) or I",
          choices=("II", "I")),
    Param("estimate_timeout", 2.0, "a payload estimate older than this (in stamps) falls back to the "
          "nominal mass", "s", gt=0.0),
    Param("reference_timeout", 0.5, "a reference older than this is stale (nothing published)",
          "s wall", gt=0.0),
    Param("state_timeout", 0.5, "a joint state older than this is stale", "s wall", gt=0.0),
    Param("sync_wait", 0.005, "a state waits this long for the reference of its stamp before the "
          "latest one is used", "s wall", ge=0.0, le=1.0),
    Param("reference_bag", "", "a reference bag written by `cablelab excite`: played from the first "
          "joint state on and published on /cdpr/reference (run the simulator with "
          "publish_reference:=false)"),
    Param("estimate_wait", 0.0, "a state waits this long for the estimate of its stamp (0 = never: "
          "use the latest; with a lock-step simulator: one deterministic chain)", "s wall",
          ge=0.0, le=10.0),
    Param("compiled_path", True, "answer the joint states from the compiled path (cablelab/csrc/"
          "controller_path.c, same law: planned rows applied in C) when it builds; not with "
          "estimate_wait > 0 or reference_bag; false, or CABLELAB_NATIVE=0: the Python path"),
), executor_params(True))
