"""Experiment design for the hopping leg (``cablelab excite``): what is designed, its limits, the
dataset of a designed motion and the closed-loop run that plays it.

The leg has no joint to move along a path: it hops. What a user (and the controller node) can
set is the desired apex height, the leg's ``/leg/reference`` (joint ``apex_height``), which the
apex-height controller (:class:`.control.ApexController`) tracks hop by hop. So the designed
motion is an apex-height schedule ``h(t)``. What it changes is the stance: how long the leg
stays on the ground against how hard it pushes. The preload F_0 is a constant force in stance and
the mass m multiplies the stance acceleration ``zdd + g``, whose mean over a stance (the
stride's impulse m g T_stride spread over T_stance) and whose shape change with the hop height;
a recording at one height sees ``m (zdd + g) - F_0`` nearly as one column (``F0`` and ``m``
confounded), a schedule over heights sees them apart.

The dataset of a schedule (:func:`motion_dataset`) is built from a library of steady hops: the
hybrid MuJoCo leg (:mod:`.sim`) under the apex controller at :data:`LEVELS` heights spread over
the range, each run until its apexes settle; the schedule's time share at each height (linear
between neighbouring levels) weighs that level's rows (rows scaled by the square root of the
share, so the information matrix is the time-weighted sum of the levels'). The transitions
between heights are left out of the design (the controller settles within a few hops; the
speed limit keeps the schedule slow against that).

Limits: the apex-height range above the touch-down height z_td (the description's geometry) in
which the controller holds the leg with its torque limit (:data:`APEX_RANGE`), and a slow rate
of change (:data:`APEX_SPEED`, :data:`APEX_ACCEL`) so the apexes follow the schedule.
"""
from __future__ import annotations

import math

import numpy as np

from ...dataset import Dataset
from ...errors import CablelabError
from ...excite import Exciter, Limits
from .topics import REFERENCE

#: apex heights a designed schedule may ask for, m above z_td: above the encoder's resolution
#: many times over, below what the controller reaches with T_max = 4 N m at P = 0.3 s
APEX_RANGE = (0.004, 0.030)
#: rate and rate of change of the apex-height schedule, m/s and m/s^2: a hop lasts about 0.5 s
#: and the controller settles within 10 hops, so the schedule moves 2 mm in that time at most
APEX_SPEED, APEX_ACCEL = 0.002, 0.002
#: heights of the steady-hop library (:func:`hop_library`)
LEVELS = 5
#: seconds each library run hops, and the seconds at its start left out (the controller settling)
LEVEL_RUN_S, LEVEL_SETTLE_S = 5.0, 2.5
JOINTS = ("apex_height",)


def excite_limits(description) -> Limits:
    from .description import leg_of

    z_td = leg_of(description).params(description.gravity).z_td
    return Limits(JOINTS, np.array([z_td + APEX_RANGE[0]]), np.array([z_td + APEX_RANGE[1]]),
                  np.array([APEX_SPEED]), np.array([APEX_ACCEL]))


def closed_loop(params, h_des, duration: float, *, z0: float | None = None, estimator_params=None,
                controller_params=None, resolution: float = 9e-5, seed: int | None = 0):
    """Simulate the leg under the apex-height controller as the nodes run it: the hybrid MuJoCo
    plant (``params``, the truth), the live estimator on the encoder height and the contact
    switch, and :class:`.control.ApexController` with the desired apex height ``h_des(t)`` (m,
    absolute, a function of time) or a constant. Returns the :class:`.sim.Trajectory` with the
    measured signals.

    Args:
        params: the simulated (true) leg. estimator_params, controller_params: the nominal
            parameters the estimator and the controller's model use (default: ``params``).
        z0: start height at rest (default z_td + the first desired apex above it).
    """
    from .control import ApexController
    from .estimator import HopEstimator
    from .hybrid import STANCE, grf, input_force
    from .sim import LegSim, Trajectory, measure, quantise

    ref = h_des if callable(h_des) else (lambda t, h=float(h_des): h)
    nominal = controller_params or params
    sim = LegSim(params, params.z_td + 0.01 if z0 is None else z0, 0.0)
    est = HopEstimator(estimator_params or nominal)
    ctl = ApexController(nominal, float(np.ravel(ref(0.0))[0]), T=1.0)
    n = int(round(duration / sim.dt)) + 1
    rows = np.empty((n, 6))
    for i in range(n):
        t = sim.t
        e = est.step(t, float(quantise(sim.z, resolution)), float(sim.phase))
        ctl.h_des = float(np.ravel(ref(t))[0])
        if e.new_apex:
            ctl.on_apex(e.apex_height)
        tau = ctl.torque(t, e.phase)
        stance = sim.phase == STANCE
        rows[i] = (t, sim.z, sim.zd, sim.phase, tau if stance else 0.0,
                   input_force(tau, sim.z, params) if stance else 0.0)
        if i < n - 1:
            sim.step(tau if stance else 0.0)
    t, z, zd, ph, tau, f_in = rows.T
    g = np.where(ph == STANCE, grf(z, zd, f_in, params), 0.0)
    traj = Trajectory(t, z, zd, ph.astype(int), tau, f_in, g, list(sim.events))
    return measure(traj, resolution=resolution, seed=seed)


def hop_library(description) -> tuple[np.ndarray, list[Dataset]]:
    """The steady-hop library of the description's leg: ``(heights, datasets)``, the
    :data:`LEVELS` desired apex heights (m, absolute) spread over :data:`APEX_RANGE` and, per
    height, the leg dataset of the controller hopping there after it settled (valid rows only).
    Cached per description."""
    key = _key(description)
    if key not in _LIBRARY:
        _LIBRARY[key] = _build_library(description)
    return _LIBRARY[key]


def _key(description):
    from .description import leg_of

    return leg_of(description), float(description.gravity)


_LIBRARY: dict = {}


def _build_library(description):
    from .dataset import dataset_from_arrays
    from .description import leg_of

    p = leg_of(description).params(description.gravity)
    heights = p.z_td + np.linspace(APEX_RANGE[0], APEX_RANGE[1], LEVELS)
    out = []
    for h in heights:
        tr = closed_loop(p, h, LEVEL_RUN_S, z0=h)
        ds = dataset_from_arrays(tr.t, tr.z_meas, tr.contact, tr.tau, description,
                                 source=f"steady hops at {1e3 * (h - p.z_td):.1f} mm")
        out.append(ds.subset(ds.valid & (ds.t >= LEVEL_SETTLE_S)))
    return heights, out


def level_shares(q: np.ndarray, heights: np.ndarray) -> np.ndarray:
    """Share of the time (samples of ``q``) spent at each library height, linear between the
    two neighbouring levels (sums to 1)."""
    x = np.interp(np.asarray(q, float).reshape(-1), heights, np.arange(len(heights)))
    lo = np.floor(x).astype(int)
    f = x - lo
    hi = np.minimum(lo + 1, len(heights) - 1)
    w = np.bincount(lo, 1 - f, len(heights)) + np.bincount(hi, f, len(heights))
    return w / max(w.sum(), 1e-300)


def _signal_names(ds: Dataset) -> list[str]:
    """The dataset's per-sample float signals (the regressor bases of :mod:`.dataset`)."""
    return [k for k, v in ds.signals.items()
            if isinstance(v, np.ndarray) and v.ndim == 1 and v.dtype.kind == "f" and len(v) == ds.n]


def _motion(parts, description, source: str) -> Dataset:
    """A design dataset from ``parts``: ``(weight, signals dict, y)`` per library level."""
    sig = {k: np.concatenate([w * s[k] for w, s, _ in parts]) for k in parts[0][1]}
    y = np.concatenate([w * yy for w, _, yy in parts])
    zd = sig["zd"]
    return Dataset(plant="leg", t=np.arange(len(y)) * 1e-3, y=y, channels=("body",), units=("N",),
                   signals=sig, actuators=("body",), act_vel=zd[:, None], act_units=(("N", "m"),),
                   inputs={"velocity": zd}, description=description, source=source)


def motion_rows(t, q, qd, qdd, description) -> Dataset:
    """The leg dataset an apex-height schedule ``q(t)`` (m) gives, row for row: the rows of the
    steady-hop library, each level's scaled by the square root of the schedule's time share
    there (module doc). The signals are the regressor bases of :mod:`.dataset`."""
    heights, dss = hop_library(description)
    w = level_shares(q, heights)
    names = _signal_names(dss[0])
    return _motion([(math.sqrt(w[j]), {k: d.signals[k] for k in names}, d.y) for j, d in enumerate(dss) if w[j] > 0],
                   description, "designed apex schedule")


def motion_dataset(t, q, qd, qdd, description) -> Dataset:
    """What the design evaluates for an apex-height schedule ``q(t)`` (m): :func:`motion_rows`
    with every level's thousands of rows replaced by the few rows of its triangular factor.

    Every leg effect's regressor column is one of the bases (a signal, or its negative), so the
    information matrix of any leg model on a level's rows is ``M^T S^T S M`` (S: the level's
    bases, one column each; M: the model's selection and signs), and ``S^T S = R^T R`` with R
    from the QR decomposition of S: the rows of R, as signals, give every model the same
    information as the level's rows (condition numbers equal to rounding, the test's oracle), at
    as many rows as there are bases. ``y`` is zero (the design needs no output). The design
    evaluates the dataset hundreds of times; built from the rows it took most of the design's
    time. (A column that is not a basis, the any-plant ``torque_sensor_offset``'s column of ones,
    is not reproduced: the rows themselves did not weigh it by the time shares either; the leg
    designs for its own effects.)"""
    heights, dss = hop_library(description)
    w = level_shares(q, heights)
    key = _key(description)
    factors = _FACTORS.get(key)
    if factors is None:
        factors = _FACTORS[key] = [_factor(d) for d in dss]
    return _motion([(math.sqrt(w[j]), f, np.zeros((len(f["zd"]), 1))) for j, f in enumerate(factors) if w[j] > 0],
                   description, "designed apex schedule (triangular factors of the levels' rows)")


def _factor(ds: Dataset) -> dict:
    """The triangular factor R (``S^T S = R^T R``) of a level's bases S, as signals by name."""
    names = _signal_names(ds)
    s = np.column_stack([ds.signals[k] for k in names])
    if not np.isfinite(s).all():
        raise CablelabError(f"{ds.source}: non-finite regressor bases in the steady-hop library")
    r = np.linalg.qr(s, mode="r")
    return {k: r[:, i].copy() for i, k in enumerate(names)}


_FACTORS: dict = {}


#: the leg's experiment design (``cablelab excite``): an apex-height schedule, registered by the
#: package; base period 50 s, the slowest change the speed limit leaves room for
EXCITER = Exciter(limits=excite_limits, motion_dataset=motion_dataset, reference_topic=REFERENCE,
                  base_hz=0.02, harmonics=3, rate_hz=10.0, stacked=False)
