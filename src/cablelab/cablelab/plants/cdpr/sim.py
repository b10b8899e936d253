"""MuJoCo simulation of a suspended CDPR built from any plant description (CONTRACT section 3; the
model itself: :mod:`cablelab.plants.cdpr.mjcf`).

Physics (all MuJoCo, no formula pasted on top):

* platform: free body (mass, inertia of a box, CoM offset), optional payload welded under it with
  its own CoM offset (001 Fig. 11);
* each cable is a spatial tendon from a winch carriage, up the swivel axis to the sheave, over
  the sheave (a cylinder on a free swivel hinge through A_i) and down to the anchor B_i. A rim
  via-site on the top of the sheave between two wraps of the same cylinder makes the path
  shortest when the sheave plane contains B_i, so the cable tension itself turns the swivel
  (a single wrap would turn it away). Without the ``pulleys`` truth effect the cable runs through
  a fixed point A_i (Model I physics);
* the cable is inextensible but can go slack: the tendon's upper length limit (a unilateral,
  slightly soft MuJoCo limit constraint) holds the paid-out length; its force is the tension;
* winch drive: a slide joint along the swivel axis whose position is the reeled-in cable s,
  driven by the motor torque through gear R and drum radius r (actuator gear R/r), with the motor
  rotor inertia J (armature J (R/r)^2), Coulomb friction F_c (frictionloss F_c R/r) and viscous
  friction F_v (damping F_v (R/r)^2), i.e. 001 eq. 15 on the motor side.

Sensors (:meth:`CdprSim.measure`): dynamometer tensions (noise, optional bias), motor torque from
current = applied torque (+ noise; includes what friction eats), motor angles and rates, platform
pose (+ noise), and the ground truth. Every truth effect is a switch in :class:`CdprTruth`.
"""
from __future__ import annotations

from dataclasses import dataclass, field, replace

import numpy as np

from ...description import Description
from ...errors import CablelabError
from ...rotations import wxyz_to_xyzw
from . import topics
from .geometry import cable_geometry
from .mjcf import RUN_LENGTH, build_mjcf

__all__ = ["CdprTruth", "CdprSim", "CdprRun", "simulate", "write_run_bag", "PAYLOADS",
           "default_description", "default_description_path", "scaled_reference",
           "without_pulley_radius", "truth_from_parameters"]

#: 001 sec. II-C: the empty platform and the two payloads M1, M2 (kg)
PAYLOADS = {"MP": 0.0, "MP+M1": 122.0, "MP+M2": 249.0}


@dataclass(frozen=True)
class CdprTruth:
    """What the simulated robot really is. Each effect can be switched off.

    Args:
        pulleys: cables run over swivel pulleys of radius ``pulley_radius`` (effect
            ``pulley_geometry``); False = fixed point exits (Model I physics).
        pulley_radius: sheave radius, m (None = the description's, or 0.15 when it has none).
        platform_mass: kg (None = the description's, else 366).
        platform_size: box (x, y, z) giving the platform inertia, m.
        platform_com: platform CoM in the platform frame, m.
        payload_mass: added mass, kg (001: 122 or 249).
        payload_com: payload CoM in the platform frame, m (offset along x_p, 001 Fig. 11).
        winch_coulomb: F_c per motor, N m (0 = effect off).
        winch_viscous: F_v per motor, N m s/rad.
        motor_inertia: rotor inertia, kg m^2.
        tension_noise: dynamometer noise std, N.
        tension_bias: per-dynamometer constant offset, N (effect ``tension_sensor_offset``).
        torque_noise: motor torque (current) noise std, N m.
        pose_noise: measured pose noise std, m.
        cable_timeconst: time constant of the cable limit constraint (stiffness), s.
        timestep: physics step, s (2 ms resolves the cable and PD dynamics: halving it changes
            no reported number at the 0.01 mm / 0.01 kg level).
        seed: noise seed.
    """

    pulleys: bool = True
    pulley_radius: float | None = None
    platform_mass: float | None = None
    platform_size: tuple = (1.5, 1.5, 1.0)
    platform_com: tuple = (0.0, 0.0, 0.0)
    payload_mass: float = 0.0
    payload_com: tuple = (0.15, 0.0, -0.6)
    winch_coulomb: float = 0.3
    winch_viscous: float = 0.002
    motor_inertia: float = 2e-4
    tension_noise: float = 5.0
    tension_bias: tuple | None = None
    torque_noise: float = 0.02
    pose_noise: float = 0.0
    cable_timeconst: float = 0.004
    timestep: float = 0.002
    seed: int = 0

    def resolved(self, desc: Description) -> "CdprTruth":
        """Fill the None defaults from the description."""
        c = desc.cdpr
        r = self.pulley_radius
        if r is None:
            r = c.pulley_radius if c.pulley_radius > 0 else 0.15
        m = self.platform_mass if self.platform_mass is not None else (c.platform_mass or 366.0)
        return replace(self, pulley_radius=float(r), platform_mass=float(m))

    @property
    def total_mass(self) -> float:
        return float(self.platform_mass) + float(self.payload_mass)

    @property
    def total_com(self) -> np.ndarray:
        """CoM of platform + payload in the platform frame, m."""
        mp, ml = float(self.platform_mass), float(self.payload_mass)
        return (mp * np.asarray(self.platform_com) + ml * np.asarray(self.payload_com)) / (mp + ml)


@dataclass
class CdprSim:
    """A running CDPR simulation (MuJoCo model + data) with contract-shaped measurements.

    Args:
        desc: plant description (any CDPR geometry).
        truth: the simulated robot's true parameters and effect switches.
        position: initial platform position (3,), m; the cables are made just taut there.
    """

    desc: Description
    truth: CdprTruth = field(default_factory=CdprTruth)
    position: np.ndarray = field(default_factory=lambda: np.array([0.0, 0.0, 1.0]))

    def __post_init__(self):
        import mujoco

        self._mj = mujoco
        self.truth = self.truth.resolved(self.desc)
        c = self.desc.cdpr
        self.n = len(c.cables)
        self.k = c.gear_ratio / c.drum_radius
        self.model = build_mjcf(self.desc, self.truth)
        self.data = mujoco.MjData(self.model)
        m = self.model
        self._reel_q = np.array([m.jnt_qposadr[m.joint(f"reel_{i}").id] for i in range(1, self.n + 1)])
        self._reel_v = np.array([m.jnt_dofadr[m.joint(f"reel_{i}").id] for i in range(1, self.n + 1)])
        self._free_q = m.jnt_qposadr[m.joint("platform").id]
        self._free_v = m.jnt_dofadr[m.joint("platform").id]
        if self.truth.pulleys:
            self._swivel_q = np.array([m.jnt_qposadr[m.joint(f"swivel_{i}").id] for i in range(1, self.n + 1)])
        self._rng = np.random.default_rng(self.truth.seed)
        self._noise = np.empty((0, 2 * self.n + 3))       # standard normals drawn in blocks (measure)
        self._noise_i = 0
        d = self.data       # views of MjData's buffers, taken once (each attribute access builds one)
        self._qpos, self._qvel, self._sens, self._act = d.qpos, d.qvel, d.sensordata, d.actuator_force
        self._ten_len, self._ten_max = d.ten_length, m.tendon_range[:, 1]
        self._free = self._qpos[self._free_q:self._free_q + 7]
        bias = self.truth.tension_bias
        self._bias = np.zeros(self.n) if bias is None else np.broadcast_to(np.asarray(bias, float), (self.n,)).copy()
        self.reset(self.position)

    def add_mass(self, mass: float, model: bool = True) -> None:
        """Load the platform with ``mass`` kg more at its own centre of mass (a payload put on
        while running: the inertia grows in proportion, the centre of mass stays); the truth's
        platform mass follows (``model`` False: only the truth, the model already has it)."""
        if model:
            b = self.model.body("platform").id
            m0 = float(self.model.body_mass[b])
            m1 = m0 + float(mass)
            if not m1 > 0:
                raise ValueError(f"platform mass would become {m1:g} kg")
            self.model.body_mass[b] = m1
            self.model.body_inertia[b] *= m1 / m0
        self.truth = replace(self.truth, platform_mass=float(self.truth.platform_mass) + float(mass))

    # ----------------------------------------------------------------------------- state
    def reset(self, position, quat=(1.0, 0.0, 0.0, 0.0)) -> None:
        """Put the platform at rest at ``position`` with taut, tension-free cables."""
        mj, m, d = self._mj, self.model, self.data
        mj.mj_resetData(m, d)
        d.qpos[self._free_q:self._free_q + 3] = position
        d.qpos[self._free_q + 3:self._free_q + 7] = quat
        if self.truth.pulleys:
            c = self.desc.cdpr
            g = cable_geometry(c.exit_points, c.anchor_points, np.asarray(position, float), None,
                               self.truth.pulley_radius, c.swivel_axes)
            d.qpos[self._swivel_q] = g.swivel_angles[0]
        m.tendon_range[:, 1] = 1000.0
        mj.mj_forward(m, d)
        m.tendon_range[:, 1] = d.ten_length.copy()
        self.cable_total = d.ten_length.copy()               # run + paid-out length at s = 0
        mj.mj_forward(m, d)

    @property
    def time(self) -> float:
        return float(self.data.time)

    def step(self, torque: np.ndarray, nstep: int = 1) -> None:
        """Apply motor torques (N m, positive reels in) for ``nstep`` physics steps."""
        self.data.ctrl[:] = torque
        self._mj.mj_step(self.model, self.data, nstep)

    def truth_pose(self):
        """(position (3,), quaternion (4,) w-x-y-z) of the platform, world."""
        q = self._free
        return q[:3].copy(), q[3:].copy()

    def slack(self) -> np.ndarray:
        """(n,) True where a cable is slack (shorter than its taut length: the tendon limit)."""
        return self._ten_len < self._ten_max - 1e-6

    def truth_state(self) -> dict:
        """Ground truth: pose, twist, tensions, swivel angles, slack flags."""
        d = self.data
        p, q = self.truth_pose()
        tension = -d.sensordata[:self.n] if d.sensordata[:self.n].sum() < 0 else d.sensordata[:self.n].copy()
        out = {"position": p, "quat": q, "velocity": d.qvel[self._free_v:self._free_v + 3].copy(),
               "tension": np.abs(tension), "slack": self.slack()}
        if self.truth.pulleys:
            out["swivel"] = d.qpos[self._swivel_q].copy()
        return out

    def measure(self) -> dict:
        """Contract measurements with sensor noise: motor angle/rate/torque (winch_1..n),
        dynamometer tension and paid-out cable length (cable_1..n), measured pose."""
        t, n = self.truth, self.n
        if self._noise_i == len(self._noise):
            # one block of draws: the same stream as three draws (n, n, 3) per call
            self._noise, self._noise_i = self._rng.standard_normal((256, 2 * n + 3)), 0
        z = self._noise[self._noise_i]
        self._noise_i += 1
        s = self._qpos[self._reel_q]
        sd = self._qvel[self._reel_v]
        paid = self.cable_total - RUN_LENGTH - s
        tension = np.abs(self._sens[:n])
        q = self._free
        return {
            "motor_angle": -self.k * paid,
            "motor_velocity": self.k * sd,
            "motor_torque": self._act + t.torque_noise * z[:n],
            "tension": tension + self._bias + t.tension_noise * z[n:2 * n],
            "cable_length": paid,
            "position": q[:3] + t.pose_noise * z[2 * n:],
            "quat": q[3:].copy(),
        }


# ================================================================================ offline runs

@dataclass
class CdprRun:
    """Arrays of one closed-loop run, sampled at the control rate (N samples, n cables).

    Contract quantities: ``t`` s; ``motor_angle``, ``motor_velocity``, ``motor_torque`` (N, n);
    ``tension``, ``cable_length`` (N, n); measured ``position`` (N, 3) and ``quat`` (N, 4, w-x-y-z);
    reference ``ref_position``, ``ref_velocity``, ``ref_acceleration`` (N, 3), ``ref_quat``;
    ``command`` (N, n) motor torque commands; the live estimate ``est_mass`` (N,), ``est_com``
    (N, 2) (NaN where none); the ground truth ``true_position`` (N, 3), ``true_quat``,
    ``true_tension`` (N, n), ``slack`` (N, n) bool, ``true_mass`` and ``true_com`` (3,).
    """

    desc: Description
    truth: CdprTruth
    arrays: dict

    def __getattr__(self, name):
        try:
            return self.__dict__["arrays"][name]
        except KeyError:
            raise AttributeError(name) from None


def simulate(desc: Description, truth: CdprTruth | None = None, *, controller: str = "pdff",
             duration: float = 60.0, rate: float = 100.0, reference=None,
             controller_config=None, estimator_config=None, progress=None,
             settle: float = 2.0) -> CdprRun:
    """Closed-loop simulation of the pick-and-place test (001 sec. II-C) as fast as possible.

    Each control period (1/rate s): measure, estimate the payload live (Model II, dynamometers,
    desired pose unless ``estimator_config`` says otherwise), compute the PD / PDFF torques, step
    the physics. The same :class:`~cablelab.plants.cdpr.live.LiveEstimator` and
    :class:`~cablelab.plants.cdpr.live.LiveController` run inside the nodes.

    Args:
        desc: plant description; truth: the simulated robot (default :class:`CdprTruth`).
        controller: "pdff" (live mass feedforward), "pd" (no feedforward) or "ff-nominal".
        duration: s; rate: control and sample rate, Hz (CAROCA: 100).
        reference: a :class:`~cablelab.plants.cdpr.trajectory.Trajectory` sampled at ``rate``
            (default: the test trajectory for ``duration``).
        progress: optional callable(fraction, elapsed s) for long runs.
        settle: s of holding the start pose under control before the recorded run starts (the
            cables are tension-free when the model is built).
    """
    import time as _time

    from .control import PdffConfig
    from .live import ControllerConfig, EstimatorConfig, LiveController, LiveEstimator
    from .trajectory import sample_trajectory

    truth = (truth or CdprTruth()).resolved(desc)
    c = desc.cdpr
    ref = reference if reference is not None else sample_trajectory(duration, rate)
    N = len(ref.t)
    sim = CdprSim(desc, truth, ref.position[0])
    nstep = max(1, int(round(1.0 / (rate * truth.timestep))))
    ccfg = controller_config or ControllerConfig(
        feedforward=controller != "pd", nominal_mass=c.platform_mass or 366.0,
        gains=PdffConfig(coulomb=truth.winch_coulomb, viscous=truth.winch_viscous))
    ctl = LiveController(c, desc.gravity, ccfg)
    est = LiveEstimator(c, desc.gravity, estimator_config or EstimatorConfig())
    n = sim.n
    keys_n = ("motor_angle", "motor_velocity", "motor_torque", "tension", "cable_length",
              "command", "true_tension")
    A = {k: np.empty((N, n)) for k in keys_n}
    A.update({k: np.empty((N, 3)) for k in ("position", "true_position")})
    A.update({k: np.empty((N, 4)) for k in ("quat", "true_quat")})
    A["slack"] = np.zeros((N, n), bool)
    A["est_mass"] = np.full(N, np.nan)
    A["est_com"] = np.full((N, 2), np.nan)
    # geometry of the whole reference at once (vectorised); the live classes take one sample
    from .geometry import CableGeometry, quat_to_matrix, wrench_matrix
    Rref = None if np.allclose(ref.orientation, [1, 0, 0, 0]) else quat_to_matrix(ref.orientation)

    def _geoms(r):
        g = cable_geometry(c.exit_points, c.anchor_points, ref.position, Rref, r, c.swivel_axes)
        return g, wrench_matrix(g)

    r_ctl = 0.0 if ccfg.model == "I" else (ccfg.gains.pulley_radius if ccfg.gains.pulley_radius is not None
                                           else c.pulley_radius)
    g_ctl, W_ctl = _geoms(r_ctl)
    pinv_ctl = np.linalg.pinv(W_ctl)
    g_est, W_est = _geoms(est._radius())
    cond_est = np.linalg.cond(W_est)

    def _one(g, k):     # what LiveController.update reads of one sample (directions, lengths, anchors)
        return CableGeometry(g.directions[k:k + 1], g.lengths[k:k + 1], g.anchors[k:k + 1], None, None,
                             None, None)

    desired = est.config.pose == "desired"
    # settle: hold the start pose with the controller until the cables carry the platform
    for _ in range(int(round(settle * rate))):
        ms = sim.measure()
        e = est.update(0.0, tensions=ms["tension"], effort=ms["motor_torque"],
                       motor_velocity=ms["motor_velocity"], position=ref.position[0],
                       quat=ref.orientation[0], condition=cond_est[0],
                       wrench=W_est[0])
        if e is not None and controller == "pdff":
            ctl.estimate(0.0, *e)
        sim.step(ctl.update(0.0, ms["motor_angle"], ms["motor_velocity"], ref.position[0],
                            ref.orientation[0], geometry=_one(g_ctl, 0), pinv=pinv_ctl[:1],
                            wrench=W_ctl[0]), nstep)
    ctl._t_est = ctl._t_filter = 0.0 if ctl._t_est is not None else None
    t0 = _time.monotonic()
    for k in range(N):
        t = k / rate
        ms = sim.measure()
        tr = sim.truth_state()
        for key in ("motor_angle", "motor_velocity", "motor_torque", "tension", "cable_length",
                    "position", "quat"):
            A[key][k] = ms[key]
        A["true_position"][k], A["true_quat"][k] = tr["position"], tr["quat"]
        A["true_tension"][k], A["slack"][k] = tr["tension"], tr["slack"]
        e = est.update(t, tensions=ms["tension"], effort=ms["motor_torque"],
                       motor_velocity=ms["motor_velocity"],
                       position=ref.position[k] if desired else ms["position"],
                       quat=ref.orientation[k] if desired else ms["quat"],
                       acceleration=ref.acceleration[k],
                       condition=cond_est[k] if desired else None,
                       wrench=W_est[k] if desired else None)
        if e is not None:
            A["est_mass"][k], A["est_com"][k] = e
            if controller == "pdff":
                ctl.estimate(t, *e)
        tau = ctl.update(t, ms["motor_angle"], ms["motor_velocity"], ref.position[k],
                         ref.orientation[k], ref.velocity[k], ref.acceleration[k],
                         geometry=_one(g_ctl, k), pinv=pinv_ctl[k:k + 1], wrench=W_ctl[k])
        A["command"][k] = tau
        sim.step(tau, nstep)
        if progress is not None and k % max(1, N // 10) == 0:
            progress(k / N, _time.monotonic() - t0)
    A["t"] = ref.t.copy()
    A["ref_position"], A["ref_velocity"] = ref.position, ref.velocity
    A["ref_acceleration"], A["ref_quat"] = ref.acceleration, ref.orientation
    A["true_mass"], A["true_com"] = truth.total_mass, truth.total_com
    return CdprRun(desc, truth, A)


def write_run_bag(run: CdprRun, path, *, overwrite: bool = True, pose: bool = True,
                  ground_truth: bool = True, commands: bool = True, every: int = 1) -> None:
    """Write a run as a contract bag (CONTRACT section 2): /plant_description, /clock,
    /cdpr/joint_states, /cdpr/cable_tensions, /cdpr/reference, optional /cdpr/platform_pose,
    /cdpr/effort_commands, /cdpr/ground_truth/{pose,payload}; ``every`` keeps every k-th sample."""
    from ...bags import BagWriter
    from ...description import dump_description

    n = run.motor_angle.shape[1]
    k = max(1, int(every))                       # keep every k-th sample (smaller reference bags)
    A = {key: (v[::k] if isinstance(v, np.ndarray) and v.ndim and len(v) == len(run.arrays["t"]) else v)
         for key, v in run.arrays.items()}
    t = A["t"]
    with BagWriter(path, overwrite=overwrite) as w:
        w.write_description(run.desc.yaml_text or dump_description(run.desc), float(t[0]))
        w.write_clock(t)
        w.write_joint_states(topics.JOINT_STATES, t, [f"winch_{i}" for i in range(1, n + 1)],
                             A["motor_angle"], A["motor_velocity"], A["motor_torque"])
        w.write_joint_states(topics.CABLE_TENSIONS, t, [f"cable_{i}" for i in range(1, n + 1)],
                             A["cable_length"], None, A["tension"])
        w.write_multidof_trajectory(topics.REFERENCE, t, A["ref_position"], wxyz_to_xyzw(A["ref_quat"]),
                                    A["ref_velocity"], None, A["ref_acceleration"], None)
        if pose:
            w.write_poses(topics.PLATFORM_POSE, t, A["position"], wxyz_to_xyzw(A["quat"]))
        if commands:
            w.write_float_arrays(topics.EFFORT_COMMANDS, t, A["command"])
        if ground_truth:
            w.write_poses(topics.GROUND_TRUTH_POSE, t, A["true_position"], wxyz_to_xyzw(A["true_quat"]))
            com = np.broadcast_to(A["true_com"], (len(t), 3))
            w.write_inertia(topics.GROUND_TRUTH_PAYLOAD, t, np.full(len(t), A["true_mass"]), com)


def truth_from_parameters(node: str, v, n: int, rate: float) -> CdprTruth:
    """The simulated CDPR's truth from the validated simulator node parameters ``v`` (the specs
    of :data:`cablelab.plants.cdpr.nodes.parameters.SIM`) for ``n`` cables at ``rate`` Hz;
    one-line errors naming ``node`` for what the specs alone cannot check (the bias length
    against the cable count, the smallest step)."""
    bias = v.tension_bias
    if len(bias) not in (1, n):
        raise CablelabError(f"{node}: parameter tension_bias:={bias}: expected 1 or {n} numbers "
                            "(one per cable) [N]")
    if 0 < v.timestep < 1e-5:
        raise CablelabError(f"{node}: parameter timestep:={v.timestep!r}: expected 0 (auto) or a step "
                            "of at least 1e-05 [s]")
    return CdprTruth(
        pulleys=v.pulleys, payload_mass=v.payload_mass, payload_com=tuple(v.payload_com),
        winch_coulomb=v.winch_coulomb, winch_viscous=v.winch_viscous,
        motor_inertia=v.motor_inertia, tension_noise=v.tension_noise,
        tension_bias=tuple(bias) if any(bias) else None, torque_noise=v.torque_noise,
        pose_noise=v.pose_noise, timestep=v.timestep or min(0.002, 1.0 / rate), seed=v.seed)


def main(argv=None) -> int:
    """``python -m cablelab.plants.cdpr.sim -o BAG``: simulate the 001 test trajectory offline (as fast as
    possible) and write a contract bag."""
    import argparse
    import sys
    import time as _time

    from ...description import load_description

    p = argparse.ArgumentParser(prog="python -m cablelab.plants.cdpr.sim", description=main.__doc__)
    p.add_argument("-o", "--out", required=True, help="bag directory to write (replaced)")
    p.add_argument("--description", default=None, help="plant description (default: CAROCA)")
    p.add_argument("--payload", type=float, default=0.0, help="payload mass, kg (001: 122, 249)")
    p.add_argument("--controller", choices=("pdff", "pd"), default="pdff")
    p.add_argument("--duration", type=float, default=60.0, help="s (60 = A->E->A)")
    p.add_argument("--rate", type=float, default=100.0, help="control and sample rate, Hz")
    p.add_argument("--no-pulleys", action="store_true", help="truth: point exits (Model I physics)")
    p.add_argument("--coulomb", type=float, default=None, help="truth winch Coulomb friction, N m")
    p.add_argument("--viscous", type=float, default=None, help="truth winch viscous friction, N m s/rad")
    p.add_argument("--bias", type=float, nargs="*", default=None, help="dynamometer biases, N")
    p.add_argument("--speed", type=float, default=1.0, help="trajectory time scale (2 = twice as fast)")
    p.add_argument("--strip-pulley-radius", action="store_true",
                   help="write the description without pulley_radius (pulleys unknown to the analysis)")
    p.add_argument("--seed", type=int, default=0)
    p.add_argument("--every", type=int, default=1, help="write every k-th sample (smaller bags)")
    a = p.parse_args(argv)
    try:
        desc = load_description(a.description or default_description_path())
        kw = {"payload_mass": a.payload, "pulleys": not a.no_pulleys, "seed": a.seed}
        if a.coulomb is not None:
            kw["winch_coulomb"] = a.coulomb
        if a.viscous is not None:
            kw["winch_viscous"] = a.viscous
        if a.bias:
            kw["tension_bias"] = tuple(a.bias)
        t0 = _time.monotonic()
        run = simulate(desc, CdprTruth(**kw), controller=a.controller, duration=a.duration / a.speed,
                       rate=a.rate, reference=scaled_reference(a.duration, a.rate, a.speed),
                       progress=lambda f, el: print(f"sim: {100 * f:3.0f} %  ETA {el / max(f, 1e-9) - el:5.1f} s",
                                                    file=sys.stderr))
        if a.strip_pulley_radius:
            run = CdprRun(without_pulley_radius(desc), run.truth, run.arrays)
        write_run_bag(run, a.out, every=a.every)
        el = _time.monotonic() - t0
        print(f"wrote {a.out}: {run.t[-1]:.1f} s simulated in {el:.1f} s ({run.t[-1] / el:.0f}x real time)")
    except CablelabError as exc:
        print(f"cablelab.plants.cdpr.sim: error: {exc}", file=sys.stderr)
        return 2
    return 0


def default_description_path() -> str:
    import os

    return os.path.join(os.path.dirname(__file__), "data", "caroca.yaml")


def default_description() -> Description:
    """The shipped CAROCA description (``cablelab/plants/cdpr/data/caroca.yaml``)."""
    from ...description import load_description

    return load_description(default_description_path())


def scaled_reference(duration: float, rate: float, speed: float):
    """The 001 test trajectory played ``speed`` times faster (velocities x speed, accelerations
    x speed^2), ``duration / speed`` s sampled at ``rate`` Hz (the strong-accelerations bags)."""
    from .trajectory import Trajectory, pick_and_place

    t = np.arange(int(round(duration / speed * rate)) + 1) / rate
    tr = pick_and_place(t * speed)
    return Trajectory(t, tr.position, tr.velocity * speed, tr.acceleration * speed ** 2)


def without_pulley_radius(desc: Description) -> Description:
    """The description with the pulley radius removed (pulleys unknown to an analysis)."""
    import dataclasses

    from ...description import dump_description, load_description
    d2 = desc.with_section("cdpr", dataclasses.replace(desc.cdpr, pulley_radius=0.0))
    text = dump_description(d2).replace("  pulley_radius: 0.0\n", "")
    return load_description(text)


if __name__ == "__main__":
    import sys

    sys.exit(main())
