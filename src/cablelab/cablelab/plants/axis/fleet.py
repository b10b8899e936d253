"""A synthetic fleet of single-axis drives (winches) for the fleet tests, demo and benchmark.

Each bag is one day of one machine running its daily test cycle: a prismatic axis (mass M, viscous friction F_v, smooth
Coulomb friction F_c tanh(qd / v_s)) tracking a multisine position reference with a PD loop plus
a nominal inertia feed-forward, integrated by :func:`scipy.integrate.solve_ivp` (RK45) -- an
integration independent of the MuJoCo truth and of the fitting code. The recorded effort is the
drive force plus a force-sensor offset plus white noise; the position carries encoder noise.

Hidden drifts (the oracle of the drift tests):

* ``friction``: F_c rises by ``rate`` (relative) per day from day ``since``:
  F_c(d) = F_c0 (1 + rate max(0, d - since)), so day ``since + 1`` is the first changed bag;
* ``offset``: a sensor offset of ``value`` appears on day ``since`` and stays.
"""
from __future__ import annotations

import dataclasses
import datetime as _dt
from pathlib import Path

import numpy as np

from . import topics

#: first day of the synthetic campaign (UTC)
EPOCH = _dt.datetime(2026, 1, 1, 8, 0, 0, tzinfo=_dt.timezone.utc)
DAY_S = 86400.0


@dataclasses.dataclass(frozen=True)
class Drift:
    """A hidden change on one machine: ``kind`` ``"friction"`` (relative ``rate`` per day from day
    ``since``) or ``"offset"`` (force offset ``value`` N from day ``since``)."""

    machine: str
    kind: str
    since: int
    rate: float = 0.0
    value: float = 0.0

    @property
    def effect(self) -> str:
        return "joint_coulomb_friction" if self.kind == "friction" else "torque_sensor_offset"

    @property
    def param(self) -> str:
        return "Fc" if self.kind == "friction" else "OF"

    @property
    def first_changed_day(self) -> int:
        """First day whose bag differs from the clean machine."""
        return self.since + 1 if self.kind == "friction" else self.since


@dataclasses.dataclass(frozen=True)
class AxisDay:
    """True parameters of one machine on one day (SI: kg, N s/m, N, m/s)."""

    mass: float = 2.0
    viscous: float = 5.0
    coulomb: float = 2.0
    v_s: float = 0.005
    offset: float = 0.0


def truth_for(machine_index: int, day: int, drifts=(), machine: str = "") -> AxisDay:
    """The true parameters of machine ``machine`` (index ``machine_index``) on ``day``: a
    per-machine spread of mass/friction plus the planted drifts."""
    rng = np.random.default_rng(1000 + machine_index)
    base = AxisDay(mass=2.0 * (1 + 0.1 * rng.uniform(-1, 1)), viscous=5.0 * (1 + 0.1 * rng.uniform(-1, 1)),
                   coulomb=2.0 * (1 + 0.1 * rng.uniform(-1, 1)))
    for d in drifts:
        if d.machine != machine:
            continue
        if d.kind == "friction":
            base = dataclasses.replace(base, coulomb=base.coulomb * (1 + d.rate * max(0, day - d.since)))
        elif d.kind == "offset" and day >= d.since:
            base = dataclasses.replace(base, offset=base.offset + d.value)
    return base


def simulate_day(truth: AxisDay, *, duration: float = 6.0, fs: float = 200.0, seed: int = 0,
                 noise_effort: float = 0.05, noise_position: float = 1e-6, cycle: int = 0):
    """One run: ``(t, q, effort)`` with t from 0 (s), q (m), measured effort (N).

    The reference is the machine's daily test cycle ``cycle``: a sum of three sines (0.4-2 Hz,
    phases drawn from ``cycle``, 0.1 m scale); ``seed`` draws the sensor noise. The drive force
    is u = M_nom rdd + K_p (r - q) + K_d (rd - qd). The plant
    M qdd = u - F_v qd - F_c tanh(qd / v_s) is integrated by solve_ivp (RK45, rtol 1e-8).
    """
    from scipy.integrate import solve_ivp

    rng = np.random.default_rng(cycle)
    freqs = np.array([0.4, 0.9, 1.7]) * (1 + 0.1 * rng.uniform(-1, 1, 3))
    amps = np.array([0.08, 0.03, 0.01])
    ph = rng.uniform(0, 2 * np.pi, 3)
    w = 2 * np.pi * freqs
    kp, kd, m_nom = 400.0, 40.0, 2.0

    def ref(t):
        s = np.sin(np.multiply.outer(t, w) + ph)
        c = np.cos(np.multiply.outer(t, w) + ph)
        return s @ amps, c @ (amps * w), -(s @ (amps * w**2))

    def force(t, q, qd):
        r, rd, rdd = ref(t)
        return m_nom * rdd + kp * (r - q) + kd * (rd - qd)

    def rhs(t, x):
        q, qd = x
        u = force(t, q, qd)
        return [qd, (u - truth.viscous * qd - truth.coulomb * np.tanh(qd / truth.v_s)) / truth.mass]

    t = np.arange(int(round(duration * fs))) / fs
    r0, rd0, _ = ref(np.array([0.0]))
    sol = solve_ivp(rhs, (0.0, t[-1]), [float(r0[0]), float(rd0[0])], t_eval=t, rtol=1e-8, atol=1e-10,
                    max_step=1.0 / fs)
    q, qd = sol.y
    u = force(t, q, qd)
    rng = np.random.default_rng(seed)
    effort = u + truth.offset + noise_effort * rng.standard_normal(t.size)
    qm = q + noise_position * rng.standard_normal(t.size)
    return t, qm, effort


def description_yaml(machine: str) -> str:
    return (f"plant: axis\nname: {machine}\naxis:\n  joint_type: prismatic\n  inertia: 2.0\n")


def machine_names(n: int) -> list[str]:
    return [f"winch-{i + 1:02d}" for i in range(n)]


def default_drifts(machines: list[str], days: int) -> list[Drift]:
    """The planted drifts of a standard fleet: friction rising on the second machine from
    40 % of the campaign, an offset appearing on the fourth at 60 % (fewer machines: fewer)."""
    out = []
    if len(machines) >= 2:
        out.append(Drift(machines[1], "friction", since=max(1, int(0.4 * days)), rate=0.05))
    if len(machines) >= 4:
        out.append(Drift(machines[3], "offset", since=max(1, int(0.6 * days)), value=0.5))
    return out


def write_fleet(root, machines: int = 6, days: int = 10, drifts=None, *, duration: float = 6.0,
                fs: float = 200.0, noise_effort: float = 0.05, progress: bool = False) -> list[Drift]:
    """Write ``root/<machine>/day-<DD>/`` rosbag2 bags (``/axis/joint_states`` + description with
    ``name`` = machine, stamps from :data:`EPOCH` + day) and return the planted drifts."""
    from ...bags import BagWriter

    root = Path(root)
    names = machine_names(machines)
    drifts = default_drifts(names, days) if drifts is None else list(drifts)
    jobs = [(i, m, d) for i, m in enumerate(names) for d in range(days)]
    if progress:
        from tqdm import tqdm

        jobs = tqdm(jobs, desc="fleet bags", unit="bag")
    for i, m, d in jobs:
        truth = truth_for(i, d, drifts, m)
        t, q, eff = simulate_day(truth, duration=duration, fs=fs, seed=7919 * i + d,
                                 noise_effort=noise_effort, cycle=i)
        t0 = EPOCH.timestamp() + d * DAY_S + 600.0 * i
        path = root / m / f"day-{d:02d}"
        path.parent.mkdir(parents=True, exist_ok=True)
        with BagWriter(path, overwrite=True) as w:
            w.write_description(description_yaml(m), t=t0)
            w.write_joint_states(topics.JOINT_STATES, t0 + t, ["joint"], position=q[:, None],
                                 effort=eff[:, None])
    return drifts


def day_time(day: int, machine_index: int = 0) -> _dt.datetime:
    """UTC start time of a synthetic bag."""
    return EPOCH + _dt.timedelta(seconds=day * DAY_S + 600.0 * machine_index)
