"""Sample-by-sample CDPR estimator and controller with input checks (ROS-free).

The nodes (payload_estimator, pd_feedforward) and the offline closed-loop simulation call these
two small state holders; all the physics is in the vectorised functions of
:mod:`cdpr_geometry`, :mod:`cdpr_estimation` and :mod:`cdpr_control`. Bad input (NaN, inf,
wrong length, negative tension, slack cable, ill-conditioned W, stale data) never produces an
output: the update returns None (estimator) or holds/falls back (controller) and says why in
``status`` (a list of (level, message); level 0 OK, 1 WARN, 2 ERROR as in diagnostic_msgs).
"""
from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

from .description import CdprDescription
from .control import PdffConfig, feedforward_tensions, motor_angles, motor_rates, pdff_torques
from .estimation import mass_com, tensions_from_torques
from .geometry import CableGeometry, pose_geometry, quat_to_matrix, wrench_matrix

__all__ = ["EstimatorConfig", "LiveEstimator", "ControllerConfig", "LiveController"]

OK, WARN, ERROR = 0, 1, 2


@dataclass(frozen=True)
class EstimatorConfig:
    """Options of the live payload estimator (001 sec. III-D, V).

    Args:
        model: "II" (pulleys, 001 eq. 6-9) or "I" (point exits, eq. 1-5).
        tensions: "dynamometer" or "motor" (motor torques, friction compensated, eq. 15).
        pose: "desired" (001's real-time choice) or "measured" (when a pose is published).
        platform_inertia: include m*a with the reference acceleration (001 eq. 10).
        coulomb, viscous: friction compensation for motor tensions, N m and N m s/rad.
        slack_tension: a tension below this is a slack cable, N.
        negative_tolerance: a tension below minus this is invalid input (not noise), N.
        max_condition: largest acceptable condition number of W.
        stale_after: inputs older than this (relative to the newest) are stale, s.
        pulley_radius: r_p for Model II (None = the description's).
    """

    model: str = "II"
    tensions: str = "dynamometer"
    pose: str = "desired"
    platform_inertia: bool = False
    coulomb: float = 0.0
    viscous: float = 0.0
    slack_tension: float = 1.0
    negative_tolerance: float = 50.0
    max_condition: float = 1e3
    stale_after: float = 0.5
    pulley_radius: float | None = None


def _geometry(desc: CdprDescription, p, R, r: float) -> CableGeometry:
    """One-sample :class:`CableGeometry` from the fast single-pose path (directions, lengths and
    anchors; the other fields are not needed live and left zero)."""
    e, L, bw = pose_geometry(desc.exit_points, desc.anchor_points, p, R, r, desc.swivel_axes)
    z = np.zeros((1, len(L)))
    return CableGeometry(e[None], L[None], bw[None], L[None], z, z, e[None] * 0.0)


def _zero_if_bad(x) -> np.ndarray:
    """A (3,) twist/acceleration; missing or non-finite -> zeros (a missing feedforward term)."""
    if x is None:
        return np.zeros(3)
    a = np.asarray(x, float)
    return a if a.shape == (3,) and np.isfinite(a).all() else np.zeros(3)


def _is_identity(q: np.ndarray) -> bool:
    return bool(abs(q[0]) == 1.0 and not q[1:].any())


def _finite_vector(x, n: int, what: str):
    if x is None:
        return None, f"{what}: missing"
    a = np.asarray(x, dtype=float).ravel()
    if a.size != n:
        return None, f"{what}: expected {n} values, got {a.size}"
    if not np.all(np.isfinite(a)):
        return None, f"{what}: NaN or inf"
    return a, None


@dataclass
class LiveEstimator:
    """Mass and CoM per sample; :meth:`update` returns (mass, (x_G, y_G)) or None."""

    desc: CdprDescription
    gravity: float = 9.81
    config: EstimatorConfig = field(default_factory=EstimatorConfig)
    status: list = field(default_factory=list)
    _cond_key: tuple | None = None
    _cond: float = 0.0

    def _radius(self) -> float:
        if self.config.model == "I":
            return 0.0
        r = self.config.pulley_radius
        return self.desc.pulley_radius if r is None else r

    def update(self, t: float, *, tensions=None, effort=None, motor_velocity=None,
               position=None, quat=None, acceleration=None, input_times: dict | None = None,
               geometry=None, condition: float | None = None):
        """One estimate from the latest inputs.

        Args:
            t: time of the estimate (stamp of the newest tension input), s.
            tensions: (n,) dynamometer tensions, N (tensions="dynamometer").
            effort, motor_velocity: (n,) motor torques N m and rates rad/s (tensions="motor").
            position, quat: pose used for W (desired or measured), m and (w, x, y, z).
            acceleration: (3,) reference acceleration for platform_inertia, m/s^2.
            input_times: {input name: stamp} used for the staleness check.
            geometry, condition: optional precomputed geometry of this pose (one sample) and
                cond(W) (batch callers compute them vectorised over the whole reference).
        """
        cfg, n = self.config, len(self.desc.cables)
        self.status = []
        if input_times:
            old = [k for k, s in input_times.items() if s is None or t - s > cfg.stale_after]
            if old:
                self.status.append((ERROR, "stale input: " + ", ".join(sorted(old))))
                return None
        if cfg.tensions == "motor":
            tau, err = _finite_vector(effort, n, "motor effort")
            qd, err2 = _finite_vector(motor_velocity, n, "motor velocity")
            if err or err2:
                self.status.append((ERROR, err or err2))
                return None
            tens = tensions_from_torques(tau, qd, self.desc.drum_radius, self.desc.gear_ratio,
                                         cfg.coulomb, cfg.viscous)
        else:
            tens, err = _finite_vector(tensions, n, "cable tensions")
            if err:
                self.status.append((ERROR, err))
                return None
        p, err = _finite_vector(position, 3, f"{cfg.pose} pose position")
        if err:
            self.status.append((ERROR, err))
            return None
        R = None
        if quat is not None:
            q, err = _finite_vector(quat, 4, f"{cfg.pose} pose orientation")
            if err or np.linalg.norm(q) < 1e-6:
                self.status.append((ERROR, err or "pose orientation: zero quaternion"))
                return None
            R = None if _is_identity(q) else quat_to_matrix(q)
        neg = np.flatnonzero(tens < -cfg.negative_tolerance)
        if neg.size:
            self.status.append((ERROR, "negative tension on cable(s) " + ", ".join(str(i + 1) for i in neg)))
            return None
        slack = np.flatnonzero(tens < cfg.slack_tension)
        if slack.size:
            self.status.append((WARN, "slack cable(s) " + ", ".join(str(i + 1) for i in slack)))
        geom = geometry if geometry is not None else _geometry(self.desc, p, R, self._radius())
        if condition is None:
            # cond(W) changes slowly with the pose: recomputed when the pose moved > 1 mm
            key = (p, None if R is None else R)
            if (self._cond_key is None or np.abs(self._cond_key[0] - p).max() > 1e-3
                    or (R is None) != (self._cond_key[1] is None)
                    or (R is not None and np.abs(self._cond_key[1] - R).max() > 1e-3)):
                self._cond = float(np.linalg.cond(wrench_matrix(geom)[0]))
                self._cond_key = key
            condition = self._cond
        cond = float(condition)
        if not np.isfinite(cond) or cond > cfg.max_condition:
            self.status.append((ERROR, f"ill-conditioned wrench matrix (cond {cond:.3g})"))
            return None
        acc = None
        if cfg.platform_inertia:
            acc, err = _finite_vector(acceleration, 3, "reference acceleration")
            if err:
                self.status.append((WARN, err + "; estimating without platform_inertia"))
                acc = None
        est = mass_com(geom, tens[None], self.gravity, None if acc is None else acc[None],
                       None if R is None else R[None])
        m, c = float(est.mass[0]), est.com[0]
        if not np.isfinite(m) or m <= 0 or not np.all(np.isfinite(c)):
            self.status.append((ERROR, f"no valid estimate (mass {m:.3g} kg)"))
            return None
        if not self.status:
            self.status.append((OK, f"mass {m:.1f} kg, cond(W) {cond:.1f}"))
        return m, c


@dataclass(frozen=True)
class ControllerConfig:
    """Options of the live PD / PDFF controller (001 sec. IV).

    Args:
        feedforward: True = PDFF (eq. 14 with the live mass), False = PD.
        nominal_mass: mass used when the live estimate is stale or invalid, kg.
        estimate_timeout: the live estimate is stale after this, s of stamps (the mass does not
            change while a load is carried: a briefly late estimator should not drop the
            feedforward to the nominal mass).
        estimate_filter: time constant of the low-pass on the live mass, s.
        valid_mass: (min, max) plausible estimate as fractions of the nominal mass.
        gains: the :class:`PdffConfig` (gains, friction compensation, tension floor).
        model: "II" or "I": geometric model of the IGM and W.
        use_com: include the estimated CoM moment in the feedforward wrench.
    """

    feedforward: bool = True
    nominal_mass: float = 366.0
    estimate_timeout: float = 2.0
    estimate_filter: float = 0.3
    valid_mass: tuple = (0.5, 3.0)
    gains: PdffConfig = field(default_factory=PdffConfig)
    model: str = "II"
    use_com: bool = True


@dataclass
class LiveController:
    """Motor torques from the latest motor state, reference and (optional) live estimate."""

    desc: CdprDescription
    gravity: float = 9.81
    config: ControllerConfig = field(default_factory=ControllerConfig)
    status: list = field(default_factory=list)
    mass: float | None = None
    com: np.ndarray = field(default_factory=lambda: np.zeros(2))
    _t_est: float | None = None
    _t_filter: float | None = None

    def estimate(self, t: float, mass: float, com=None) -> bool:
        """Feed one live estimate (stamp t); rejected (False) when invalid."""
        lo, hi = self.config.valid_mass
        nom = self.config.nominal_mass
        if not np.isfinite(mass) or not (lo * nom <= mass <= hi * nom):
            return False
        c = np.zeros(2) if com is None else np.asarray(com, float)[:2]
        if not np.all(np.isfinite(c)):
            c = self.com
        if self.mass is None or self._t_filter is None:
            self.mass, self.com = float(mass), c
        else:
            a = min(1.0, max(0.0, t - self._t_filter) / max(self.config.estimate_filter, 1e-9))
            self.mass += a * (mass - self.mass)
            self.com = self.com + a * (c - self.com)
        self._t_est = self._t_filter = t
        return True

    def update(self, t: float, q, qdot, position, quat=None, velocity=None, acceleration=None,
               geometry=None, pinv=None):
        """Torques (n,) N m, or None when the motor state or reference is unusable
        (``geometry``/``pinv``: optional precomputed geometry and W^+ of this reference pose)."""
        cfg, n, d = self.config, len(self.desc.cables), self.desc
        self.status = []
        q, e1 = _finite_vector(q, n, "motor angles")
        qdot, e2 = _finite_vector(qdot, n, "motor velocities")
        p, e3 = _finite_vector(position, 3, "reference position")
        if e1 or e2 or e3:
            self.status.append((ERROR, e1 or e2 or e3))
            return None
        v = _zero_if_bad(velocity)
        a = _zero_if_bad(acceleration)
        R = None
        if quat is not None and not _is_identity(np.asarray(quat, float)):
            R = quat_to_matrix(np.asarray(quat, float))
        r = 0.0 if cfg.model == "I" else (cfg.gains.pulley_radius if cfg.gains.pulley_radius is not None
                                           else d.pulley_radius)
        geom = geometry if geometry is not None else _geometry(d, p, R, r)
        q_des = motor_angles(geom.lengths, d.drum_radius, d.gear_ratio)[0]
        qd_des = motor_rates(geom, v, d.drum_radius, d.gear_ratio)[0]
        t_ff = None
        if cfg.feedforward:
            fresh = self._t_est is not None and t - self._t_est <= cfg.estimate_timeout
            if fresh:
                m, com = self.mass, self.com
            else:
                m, com = cfg.nominal_mass, np.zeros(2)
                self.status.append((WARN, "live mass estimate stale or missing: nominal mass "
                                    f"{m:.0f} kg in the feedforward"))
            c3 = np.array([com[0], com[1], 0.0]) if cfg.use_com else None
            t_ff = feedforward_tensions(geom, m, a[None], self.gravity, c3, cfg.gains.preload,
                                        cfg.gains.min_tension, pinv=pinv)[0]
        tau = pdff_torques(q, qdot, q_des, qd_des, t_ff, d.drum_radius, d.gear_ratio, cfg.gains)
        if not self.status:
            self.status.append((OK, "PDFF" if cfg.feedforward else "PD"))
        return tau
