"""Sample-by-sample CDPR estimator and controller with input checks (ROS-free).

The nodes (payload_estimator, pd_feedforward) and the offline closed-loop simulation call these
two small state holders; all the physics is in the vectorised functions of
:mod:`.geometry`, :mod:`.estimation` and :mod:`.control`. Bad input (NaN, inf,
wrong length, negative tension, slack cable, ill-conditioned W, stale data) never produces an
output: the update returns None (estimator) or holds/falls back (controller) and says why in
``status`` (a list of (level, message); level 0 OK, 1 WARN, 2 ERROR as in diagnostic_msgs).
"""
from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

from .description import CdprDescription
from .control import PdffConfig, pdff_torques
from .estimation import mass_com_from_wrench, tensions_from_torques, winch_friction
from .geometry import pose_geometry, quat_to_matrix, wrench_matrix

__all__ = ["EstimatorConfig", "LiveEstimator", "ControllerConfig", "LiveController", "ReferenceTerms",
           "ReferencePlan"]

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


def _zero_if_bad(x) -> np.ndarray:
    """A (3,) twist/acceleration; missing or non-finite -> zeros (a missing feedforward term)."""
    if x is None:
        return np.zeros(3)
    a = np.asarray(x, float)
    return a if a.shape == (3,) and np.isfinite(a).all() else np.zeros(3)


def _wrench_one(d: np.ndarray, b: np.ndarray) -> np.ndarray:
    """(6, n) wrench matrix of one pose (001 eq. 4 / 7) from directions d (n, 3) and anchors
    b (n, 3): the single-sample form of :func:`~.geometry.wrench_matrix`, without its batch axis."""
    W = np.empty((6, len(d)))
    W[:3] = d.T
    W[3] = b[:, 1] * d[:, 2] - b[:, 2] * d[:, 1]
    W[4] = b[:, 2] * d[:, 0] - b[:, 0] * d[:, 2]
    W[5] = b[:, 0] * d[:, 1] - b[:, 1] * d[:, 0]
    return W


def _feedforward_one(W: np.ndarray, mass: float, acc: np.ndarray, gravity: float, com, preload: float,
                     min_tension: float, pinv: np.ndarray | None) -> np.ndarray:
    """001 eq. 14 for one pose: :func:`~.control.feedforward_tensions` on a (6, n) W (and optional
    (n, 6) W^+) without the batch axis (the live controller calls it at 1 kHz)."""
    f = acc + np.array([0.0, 0.0, gravity])
    w = np.empty(6)
    w[:3] = mass * f
    if com is None:
        w[3:] = 0.0
    else:
        cx, cy, cz = com
        w[3:] = mass * np.array([cy * f[2] - cz * f[1], cz * f[0] - cx * f[2], cx * f[1] - cy * f[0]])
    rhs = w - preload * W.sum(1)
    if pinv is None:   # W^+ rhs = W^T (W W^T)^-1 rhs for a full-row-rank W (6 x n, n >= 6)
        t = preload + W.T @ np.linalg.solve(W @ W.T, rhs)
    else:
        t = preload + pinv @ rhs
    return np.maximum(t, min_tension)


def _stale_mass(nominal: float) -> tuple[int, str]:
    return (WARN, f"live mass estimate stale or missing: nominal mass {nominal:.0f} kg in the feedforward")


def _is_identity(q: np.ndarray) -> bool:
    return bool(abs(q[0]) == 1.0 and not q[1:].any())


def _finite_vector(x, n: int, what: str):
    if x is None:
        return None, f"{what}: missing"
    a = np.asarray(x, dtype=float).ravel()
    if a.size != n:
        return None, f"{what}: expected {n} values, got {a.size}"
    if not np.isfinite(a).all():
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
               geometry=None, condition: float | None = None, wrench=None):
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
            wrench: optional precomputed (6, n) wrench matrix W of this pose (then ``geometry``
                is not needed).
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
        if tens.min() < cfg.slack_tension:
            neg = np.flatnonzero(tens < -cfg.negative_tolerance)
            if neg.size:
                self.status.append((ERROR, "negative tension on cable(s) " + ", ".join(str(i + 1) for i in neg)))
                return None
            slack = np.flatnonzero(tens < cfg.slack_tension)
            self.status.append((WARN, "slack cable(s) " + ", ".join(str(i + 1) for i in slack)))
        if wrench is not None:
            W = wrench
        elif geometry is not None:
            W = wrench_matrix(geometry)[0]
        else:
            d, _L, b = pose_geometry(self.desc.exit_points, self.desc.anchor_points, p, R, self._radius(),
                                     self.desc.swivel_axes)
            W = _wrench_one(d, b)
        if condition is None:
            # cond(W) changes slowly with the pose: recomputed when the pose moved > 1 mm
            key = (p, None if R is None else R)
            if (self._cond_key is None or np.abs(self._cond_key[0] - p).max() > 1e-3
                    or (R is None) != (self._cond_key[1] is None)
                    or (R is not None and np.abs(self._cond_key[1] - R).max() > 1e-3)):
                self._cond = float(np.linalg.cond(W))
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
        wt = W @ tens                                         # cable wrench W t (001 eq. 12)
        if acc is None and R is None:
            # static, level: 001 eq. 13 on one sample (mass_com_from_wrench's first branch)
            mg = float(wt[2])
            m = mg / self.gravity
            c = np.array([-wt[4] / mg, wt[3] / mg]) if m > 0 and np.isfinite(m) else np.full(2, np.nan)
        else:
            est = mass_com_from_wrench(wt[None], self.gravity, None if acc is None else acc[None],
                                       None if R is None else R[None])      # 001 eq. 13 with eq. 10
            m, c = float(est.mass[0]), est.com[0]
        if not np.isfinite(m) or m <= 0 or not np.isfinite(c).all():
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


@dataclass(frozen=True)
class ReferenceTerms:
    """What :meth:`LiveController.prepare` computed for the reference of stamp ``t``: desired
    motor angles ``q_des`` (rad) and rates ``qd_des`` (rad/s), feedforward tensions
    ``tensions_ff`` (N, None for PD) and the status lines of the preparation."""

    t: float
    q_des: np.ndarray
    qd_des: np.ndarray
    tensions_ff: np.ndarray | None
    status: list


@dataclass(frozen=True)
class ReferencePlan:
    """What :meth:`LiveController.plan` computed for N reference stamps at once (level platform):
    the terms of the law that depend on the reference only, not on the motor state nor on the
    live estimate, so that a control loop whose reference is known ahead does the geometry and
    the W^+ of eq. 14 vectorised over a block of periods instead of once per period.

    With ``q_d``, ``q_d'`` the IGM and rates of :meth:`LiveController.prepare` and
    ``M = W^T (W W^T)^-1`` (n, 6) the right inverse of W, 001 eq. 14 for a mass m and CoM
    (c_x, c_y, 0) is ``max(t_p + M (w - t_p W 1), t_min)`` with w = m [f; c x f], f = a + g: linear
    in (1, m, m c_x, m c_y) with the rows of ``ff`` (base = t_p - t_p M W 1, then M [f; 0],
    M [0; (0, -f_z, f_y)], M [0; (f_z, 0, -f_x)]).

    Attributes (N stamps, n cables): ``t`` (N,) stamps, s; ``reference`` the (position, velocity,
    acceleration) rows it was made from; ``valid`` (N,) False where the reference position is not
    finite (the law then takes the per-sample path, which says why); ``pd``
    (N, n) ``kp q_d + kd q_d'``; ``friction`` (N, n) the friction compensation of eq. 15 on q_d';
    ``ff`` (N, 4, n) the feedforward rows above (None for PD).
    """

    t: np.ndarray
    reference: tuple
    valid: np.ndarray
    pd: np.ndarray
    friction: np.ndarray
    ff: np.ndarray | None

    def __len__(self) -> int:
        return len(self.t)


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

    def __post_init__(self):
        d = self.desc        # the description's arrays, built once (its properties build them per call)
        self._exit, self._anchor, self._swivel = d.exit_points, d.anchor_points, d.swivel_axes
        self._anchor_reach = 2.0 * np.abs(self._anchor[:, :2]).max()
        self._coef = np.zeros(4)            # (1, m, m c_x, m c_y) of the planned feedforward
        self._coef_key = None
        self._stale = None                  # (nominal mass, its status line)

    def _model_radius(self) -> float:
        cfg = self.config
        if cfg.model == "I":
            return 0.0
        return cfg.gains.pulley_radius if cfg.gains.pulley_radius is not None else self.desc.pulley_radius

    def estimate(self, t: float, mass: float, com=None) -> bool:
        """Feed one live estimate (stamp t); rejected (False) when invalid. A CoM that is not
        finite or lies farther from the platform origin than twice its farthest cable anchor (in
        x or y: no load on this platform can put it there) is ignored: the previous CoM stays."""
        lo, hi = self.config.valid_mass
        nom = self.config.nominal_mass
        if not np.isfinite(mass) or not (lo * nom <= mass <= hi * nom):
            return False
        c = np.zeros(2) if com is None else np.asarray(com, float)[:2]
        if not np.all(np.isfinite(c)) or np.abs(c).max() > self._anchor_reach:
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
               geometry=None, pinv=None, wrench=None):
        """Torques (n,) N m, or None when the motor state or reference is unusable
        (``geometry``/``pinv``/``wrench``: optional precomputed geometry (one sample), W^+ (1, n, 6)
        and W (6, n) of this reference pose).

        One sample, no batch axis: :meth:`prepare` (the reference terms) then :meth:`law` (the
        motor state terms)."""
        ref = self.prepare(t, position, quat, velocity, acceleration, geometry, pinv, wrench)
        return None if ref is None else self.law(ref, q, qdot)

    def prepare(self, t: float, position, quat=None, velocity=None, acceleration=None,
                geometry=None, pinv=None, wrench=None) -> "ReferenceTerms | None":
        """The terms of the law that depend on the reference of stamp ``t`` and the live estimate
        only, not on the measured motor state: the IGM q_d = -(R/r) l, the rates q_d' = (R/r) d . v
        (001 eq. 5) and the feedforward tensions of 001 eq. 14. A node computes them as soon as
        the reference of the next stamp is known, off the state -> command path, and :meth:`law`
        finishes the command when the state arrives. None when the reference is unusable
        (:attr:`status` says why)."""
        cfg, d = self.config, self.desc
        self.status = []
        p, e3 = _finite_vector(position, 3, "reference position")
        if e3:
            self.status.append((ERROR, e3))
            return None
        v = _zero_if_bad(velocity)
        a = _zero_if_bad(acceleration)
        R = None
        if quat is not None and not _is_identity(np.asarray(quat, float)):
            R = quat_to_matrix(np.asarray(quat, float))
        if geometry is not None:
            dirs, L, b = geometry.directions[0], geometry.lengths[0], geometry.anchors[0]
        else:
            dirs, L, b = pose_geometry(self._exit, self._anchor, p, R, self._model_radius(), self._swivel)
        k = d.gear_ratio / d.drum_radius
        q_des = -k * L                                    # control.motor_angles
        qd_des = k * (dirs @ v)                           # control.motor_rates (no angular velocity)
        t_ff = None
        if cfg.feedforward:
            fresh = self._t_est is not None and t - self._t_est <= cfg.estimate_timeout
            if fresh:
                m, com = self.mass, self.com
            else:
                m, com = cfg.nominal_mass, np.zeros(2)
                self.status.append(_stale_mass(m))
            c3 = (com[0], com[1], 0.0) if cfg.use_com else None
            W = wrench if wrench is not None else _wrench_one(dirs, b)
            t_ff = _feedforward_one(W, m, a, self.gravity, c3, cfg.gains.preload, cfg.gains.min_tension,
                                    None if pinv is None else pinv[0])
        return ReferenceTerms(t, q_des, qd_des, t_ff, list(self.status))

    def law(self, ref: "ReferenceTerms", q, qdot):
        """Torques (n,) N m of 001 Fig. 6 (PD on the motor angles + the prepared feedforward and
        friction compensation, :func:`~.control.pdff_torques`) for the measured motor state, or
        None when it is unusable (:attr:`status` says why)."""
        n, d = len(self.desc.cables), self.desc
        self.status = list(ref.status)
        q, e1 = _finite_vector(q, n, "motor angles")
        qdot, e2 = _finite_vector(qdot, n, "motor velocities")
        if e1 or e2:
            self.status.append((ERROR, e1 or e2))
            return None
        tau = pdff_torques(q, qdot, ref.q_des, ref.qd_des, ref.tensions_ff, d.drum_radius, d.gear_ratio,
                           self.config.gains)
        if not self.status:
            self.status.append((OK, "PDFF" if self.config.feedforward else "PD"))
        return tau

    def plan(self, t, position, velocity=None, acceleration=None) -> ReferencePlan:
        """The reference terms of N stamps ``t`` (N,) of a level platform at once (:class:`ReferencePlan`):
        :meth:`prepare`'s arithmetic vectorised over the stamps, without the live estimate.
        ``position``, ``velocity``, ``acceleration``: (N, 3); a velocity or acceleration row that
        is not finite counts as zero, as in :meth:`prepare`."""
        cfg, d, g = self.config, self.desc, self.config.gains
        t = np.asarray(t, float)
        reference = (position, velocity, acceleration)
        p = np.asarray(position, float).reshape(-1, 3)
        valid = np.isfinite(p).all(1)
        p = np.where(valid[:, None], p, 0.0)

        def rows(x):
            if x is None:
                return np.zeros_like(p)
            x = np.asarray(x, float).reshape(-1, 3)
            return np.where(np.isfinite(x).all(1)[:, None], x, 0.0)

        v, a = rows(velocity), rows(acceleration)
        dirs, L, b = pose_geometry(self._exit, self._anchor, p[:, None, :], None, self._model_radius(), self._swivel)
        k = d.gear_ratio / d.drum_radius
        q_des = -k * L
        qd_des = k * np.einsum("tni,ti->tn", dirs, v)
        pd = g.kp * q_des + g.kd * qd_des
        friction = winch_friction(qd_des, g.coulomb, g.viscous)
        ff = None
        if cfg.feedforward:
            W = np.empty((len(p), 6, dirs.shape[1]))
            W[:, :3] = dirs.transpose(0, 2, 1)                 # _wrench_one on every stamp
            W[:, 3] = b[:, 1] * dirs[..., 2] - b[:, 2] * dirs[..., 1]
            W[:, 4] = b[:, 2] * dirs[..., 0] - b[:, 0] * dirs[..., 2]
            W[:, 5] = b[:, 0] * dirs[..., 1] - b[:, 1] * dirs[..., 0]
            M = np.linalg.solve(W @ W.transpose(0, 2, 1), W).transpose(0, 2, 1)     # (N, n, 6)
            f = a + np.array([0.0, 0.0, self.gravity])
            zero = np.zeros(len(p))
            ff = np.empty((len(p), 4, W.shape[2]))
            ff[:, 0] = g.preload - g.preload * np.einsum("tij,tj->ti", M, W.sum(2))
            ff[:, 1] = np.einsum("tij,tj->ti", M[..., :3], f)
            ff[:, 2] = np.einsum("tij,tj->ti", M[..., 3:], np.stack([zero, -f[:, 2], f[:, 1]], 1))
            ff[:, 3] = np.einsum("tij,tj->ti", M[..., 3:], np.stack([f[:, 2], zero, -f[:, 0]], 1))
        return ReferencePlan(t, reference, valid, pd, friction, ff)

    def estimate_weights(self) -> tuple[float, np.ndarray]:
        """``(t_est, c)``: the stamp of the live estimate (NaN before one) and the weights
        ``c = (1, m, m c_x, m c_y)`` (c = 0 without ``use_com``) of the four feedforward tension
        rows of a :class:`ReferencePlan`: :meth:`planned_law` uses ``c`` for a row of stamp t
        when ``t - t_est <= estimate_timeout``, else the nominal mass's ``(1, m_nominal, 0, 0)``;
        the compiled path (:mod:`.controller_path`) is given these and does the same."""
        if self.mass is None or self._t_est is None:
            return float("nan"), np.array([1.0, self.config.nominal_mass, 0.0, 0.0])
        m = self.mass
        cx, cy = (self.com[0], self.com[1]) if self.config.use_com else (0.0, 0.0)
        return float(self._t_est), np.array([1.0, m, m * cx, m * cy])

    def planned_status(self, t: float) -> list:
        """The :attr:`status` :meth:`planned_law` leaves after a valid row of stamp ``t`` and a
        good motor state (PD; PDFF with a fresh estimate; else the nominal-mass warning)."""
        cfg = self.config
        if not cfg.feedforward:
            return [(OK, "PD")]
        if self._t_est is not None and t - self._t_est <= cfg.estimate_timeout:
            return [(OK, "PDFF")]
        return [_stale_mass(cfg.nominal_mass)]

    def planned_law(self, plan: ReferencePlan, i: int, q, qdot):
        """Torques (n,) N m for row ``i`` of ``plan`` and the measured motor state: what
        :meth:`prepare` then :meth:`law` give for that stamp, to round-off, with a few operations
        on (n,) arrays (the control loop's per-period path). A row that is not valid, or a motor
        state that is not two finite float (n,) arrays, takes :meth:`prepare` and :meth:`law`
        (which check and say why)."""
        cfg, g = self.config, self.config.gains
        n = plan.pd.shape[1]
        t = float(plan.t[i])
        if (not plan.valid[i] or type(q) is not np.ndarray or type(qdot) is not np.ndarray
                or q.shape != (n,) or qdot.shape != (n,) or q.dtype != float or qdot.dtype != float
                or not np.isfinite(q @ qdot)):
            # (q . q' is finite exactly when every term is, barring overflow, which also lands here)
            p, v, a = (None if x is None else x[i] for x in plan.reference)
            ref = self.prepare(t, p, None, v, a)
            return None if ref is None else self.law(ref, q, qdot)
        k = self.desc.drum_radius / self.desc.gear_ratio
        tau = plan.pd[i] - g.kp * q
        tau -= g.kd * qdot
        if plan.ff is not None:
            fresh = self._t_est is not None and t - self._t_est <= cfg.estimate_timeout
            if fresh:
                m, com = self.mass, self.com
                key = (m, com[0], com[1]) if cfg.use_com else (m, 0.0, 0.0)
            else:
                key = (cfg.nominal_mass, 0.0, 0.0)
            if key != self._coef_key:
                m, cx, cy = key
                self._coef[:] = (1.0, m, m * cx, m * cy)
                self._coef_key = key
            t_ff = self._coef @ plan.ff[i]
            np.maximum(t_ff, g.min_tension, out=t_ff)
            t_ff *= k
            tau += t_ff
            if fresh:
                self.status = [(OK, "PDFF")]
            else:
                if self._stale is None or self._stale[0] != cfg.nominal_mass:
                    self._stale = (cfg.nominal_mass, _stale_mass(cfg.nominal_mass))
                self.status = [self._stale[1]]
        else:
            self.status = [(OK, "PD")]
        np.maximum(tau, k * g.min_tension, out=tau)
        tau += plan.friction[i]
        np.maximum(tau, -g.max_torque, out=tau)
        return np.minimum(tau, g.max_torque, out=tau)

