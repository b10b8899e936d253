"""The ROS parameters of the suspended platform's nodes, declared once (the way
generate_parameter_library keeps a node's parameters in a YAML file beside it): :data:`SIM`
(``cable_sim_node``), :data:`ESTIMATOR` (``payload_estimator``) and :data:`CONTROLLER`
(``pd_feedforward``), typed specs (:class:`cablelab.ros.params.Param`) each node declares with
descriptors and validates (``NODE --plant suspended --help`` and docs/nodes.md list them)."""
from __future__ import annotations

from .. import topics
from ..params import VARIANTS, parameter_set
from ....errors import CablelabError
from ....ros.params import START_GATE, Param, executor_params, markers_rate, merge

__all__ = ["SIM", "ESTIMATOR", "CONTROLLER", "VARIANT", "check_sim"]

#: the simulator's and the controller's ``variant``
VARIANT = Param("variant", "licas", "which platform: LiCAS or CRANEbot", choices=VARIANTS)

#: ``cable_sim_node --plant suspended``: model, start, arm drives, lock-step, sensors
SIM = merge((
    VARIANT,
    Param("model", "virtual", "the virtual-joint model or the four-tendon truth plant",
          choices=("virtual", "truth")),
    Param("start_swing_x", 0.0, "initial swing about x", "rad", ge=-1.5, le=1.5),
    Param("start_swing_y", 0.0, "initial swing about y", "rad", ge=-1.5, le=1.5),
    Param("start_yaw", 0.0, "initial yaw", "rad", ge=-3.2, le=3.2),
    Param("arm_input", "reference", "arm drives: position servos following /suspended/reference "
          "or torque motors driven by /suspended/effort_commands", choices=("reference", "effort")),
    Param("pose_noise", 0.0, "standard deviation of the measured platform position", "m",
          ge=0.0, le=10.0),
    Param("rate", 100.0, "publishing rate = command sampling (use 1000 with arm_input effort)",
          "Hz", ge=1.0, le=10000.0),
    Param("duration", 0.0, "simulated time after which the node exits (0 = run for ever)", "s",
          ge=0.0),
    Param("lockstep", False, "after a state, wait for the command answering it (needs "
          "arm_input effort)"),
    Param("lockstep_timeout", 10.0, "lock-step: without an answer for this long, real time with "
          "zero torque until commands flow again", "s wall", gt=0.0),
    Param("lockstep_resend", 0.25, "lock-step: the state is resent this often while waiting",
          "s wall", gt=0.0, le=60.0),
    Param("command_timeout", 0.5, "an effort command older than this means zero torque (WARN)",
          "s wall", gt=0.0),
    Param("imu", True, "publish /suspended/imu (orientation, gyro, accelerometer in the "
          "platform frame)"),
    markers_rate(f"{topics.MARKERS}: cables coloured by tension, platform, arms"),
), START_GATE, executor_params(True))



def check_sim(v) -> None:
    """The rule between :data:`SIM`'s validated values ``v``: lock-step waits for effort
    commands, so ``lockstep`` needs ``arm_input:=effort`` (one-line error otherwise)."""
    if v.lockstep and v.arm_input != "effort":
        raise CablelabError("cable_sim_node suspended: parameter lockstep=true needs "
                            "arm_input=effort (lock-step waits for effort commands)")


#: ``payload_estimator --plant suspended``: the swing estimator and its inputs' timeouts
ESTIMATOR = merge((
    Param("suspension_point", [float(x) for x in parameter_set("licas").S], "suspension point "
          "S [x, y, z] (default: the LiCAS repo set)", "m", length=(3,), ge=-1e3, le=1e3),
    Param("rest_position", [float("nan")] * 3, "rest position [x, y, z] (NaN: the mean over the "
          "first rest_window s)", "m", length=(3,), ge=-1e3, le=1e3, nan=True),
    Param("rest_yaw", float("nan"), "rest yaw (NaN: the mean over the first rest_window s)", "rad",
          ge=-10.0, le=10.0, nan=True),
    Param("rest_window", 2.0, "time the rest pose is averaged over", "s", gt=0.0, le=3600.0),
    Param("imu_max_lag", 0.05, "yaw and yaw rate come from the IMU for poses within this of an "
          "IMU sample (stamps)", "s", ge=0.0, le=10.0),
    Param("velocity_tau", 0.05, "time constant smoothing the swing rates", "s", gt=0.0, le=10.0),
    Param("pose_timeout", 0.5, "a pose older than this is stale", "s wall", gt=0.0),
    Param("imu_timeout", 0.5, "an IMU sample older than this is stale (once the IMU was seen)",
          "s wall", gt=0.0),
), executor_params(True))

#: ``pd_feedforward --plant suspended``: excitation, sway damping, pose synchronisation
CONTROLLER = merge((
    VARIANT,
    Param("excitation", "none", "built-in excitation of 000 Fig. 7 added to the reference",
          choices=("none", "x", "y", "z"),
          convert=lambda v: "y" if v is True else v),     # (YAML reads a bare y as true)
    Param("excitation_level", 1, "level of the built-in excitation", ge=0, le=2),
    Param("sway_damping", 0.0, "sway damping gain k_s on the r_y rate of /suspended/swing_estimate",
          ge=0.0, le=1e3),
    Param("estimate_stale", 0.2, "a swing estimate older than this (stamps) turns sway damping "
          "off", "s", gt=0.0),
    Param("pose_sync", False, "answer a joint state only once the pose of the same stamp "
          "arrived (while poses flow)"),
), executor_params(True))
