"""Randomized diagnosis cases, generated WITHOUT the fitting code (bench_diagnosis.py).

Each case is a drive recording as a real machine would produce it, written as an MCAP bag:

* plant: a position-controlled single axis (prismatic linear drive, or a revolute joint with a
  gravity load; a "slew" flavour with a large inertia, slow moves and 100 Hz as a crane slew axis).
* truth: integrated with :func:`scipy.integrate.solve_ivp` (LSODA, stiff-capable) from
  ``M qdd = u - F(qd) - mc g sin q`` with a PD + acceleration-feedforward controller tracking a
  reference; friction is the SMOOTH law
  ``F(v) = Fv v + tanh(v / eps) (Fc + (Fs - Fc) exp(-(v / vs)^2))`` (narrow tanh band eps,
  optional Stribeck bump), never the ``sign`` the fitting code uses.
* reference: point-to-point minimum-jerk moves at several speed levels, or chirp bursts, both with
  20-50 % of the time at rest.
* sensors: the measured effort is the motor command ``u(t - tau) + OF`` plus coloured (AR(1))
  noise and sparse outliers; the position is encoder-quantized; the velocity is recorded in some
  cases and absent (NaN) in others; 100 Hz or 1 kHz.

The hidden effects (what the nominal model ``axis_inertia + joint_viscous_friction (+
axis_gravity)`` lacks) are drawn from ``joint_coulomb_friction``, ``torque_sensor_offset``,
``time_delay`` (one or two of them), plus control cases with nothing hidden.
"""
from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np
import scipy.integrate

from cases_common import coloured_noise, min_jerk, quantize

G = 9.81
#: hidden-effect menu of the axis cases: effect id -> the true parameter checked
TRUE_PARAM = {"joint_coulomb_friction": "Fc", "torque_sensor_offset": "OF", "time_delay": "tau"}
ONE = [("joint_coulomb_friction",), ("torque_sensor_offset",), ("time_delay",)]
TWO = [("joint_coulomb_friction", "torque_sensor_offset"), ("joint_coulomb_friction", "time_delay"),
       ("torque_sensor_offset", "time_delay")]


@dataclass
class Case:
    """One randomized case (all SI)."""

    seed: int
    flavour: str                 # "linear", "pendulum", "slew"
    fs: float                    # recording rate, Hz
    duration: float              # s
    profile: str                 # "ptp" or "chirp"
    rest_fraction: float         # target share of time at rest
    hidden: tuple                # hidden effect ids (empty = control)
    truth: dict = field(default_factory=dict)   # M, Fv, Fc, Fs, vs, eps, mc, OF, tau
    velocity_recorded: bool = False
    quantum: float = 0.0         # encoder resolution, m or rad
    noise_rel: float = 0.02      # effort noise std / effort rms
    ar: float = 0.0              # AR(1) coefficient of the effort noise
    outlier_rate: float = 0.0    # share of samples with a 10-sigma spike
    vmax: float = 1.0            # peak reference speed, m/s or rad/s

    @property
    def kind(self) -> str:
        return "prismatic" if self.flavour == "linear" else "revolute"

    def description_yaml(self) -> str:
        t = self.truth
        y = f"plant: axis\naxis:\n  joint_type: {self.kind}\n  inertia: {t['M']:.6g}\n"
        if self.kind == "revolute" and t.get("mc", 0.0) > 0:
            y += f"  gravity_moment: {t['mc']:.6g}\n"
        return y

    def label(self) -> str:
        return "+".join(h.replace("joint_", "").replace("torque_sensor_", "") for h in self.hidden) or "control"


def draw_case(seed: int, kind: str | None = None) -> Case:
    """A random case. ``kind``: "control", "one", "two" (default: drawn 20/50/30 %)."""
    rng = np.random.default_rng(seed)
    if kind is None:
        kind = rng.choice(["control", "one", "two"], p=[0.2, 0.5, 0.3])
    hidden = () if kind == "control" else (ONE[rng.integers(3)] if kind == "one" else TWO[rng.integers(3)])
    flavour = str(rng.choice(["linear", "pendulum", "slew"], p=[0.45, 0.3, 0.25]))
    if flavour == "linear":
        M, Fv, vmax = rng.uniform(1, 20), rng.uniform(2, 40), rng.uniform(0.2, 0.8)
        mc, quantum = 0.0, 10.0 ** rng.uniform(-6, -5)
        fs = float(rng.choice([100.0, 1000.0], p=[0.3, 0.7]))
    elif flavour == "pendulum":
        M, Fv, vmax = rng.uniform(0.1, 1.0), rng.uniform(0.05, 0.5), rng.uniform(1.0, 3.0)
        mc, quantum = rng.uniform(0.1, 0.6), 2 * np.pi / 2 ** rng.integers(14, 18)
        fs = float(rng.choice([100.0, 1000.0], p=[0.3, 0.7]))
    else:  # crane slew axis: large inertia, slow, 100 Hz
        M, Fv, vmax = rng.uniform(50, 500), rng.uniform(20, 300), rng.uniform(0.1, 0.4)
        mc, quantum = 0.0, 2 * np.pi / 2 ** rng.integers(16, 20)
        fs = 100.0
    # effort scale: inertial + viscous force at the reference speed
    a_typ = vmax * 2.0
    f_typ = M * a_typ + Fv * vmax + mc * G
    truth = {"M": M, "Fv": Fv, "mc": mc, "Fc": 0.0, "Fs": 0.0, "vs": 0.1 * vmax,
             "eps": rng.uniform(0.002, 0.01) * vmax, "OF": 0.0, "tau": 0.0}
    if "joint_coulomb_friction" in hidden:
        truth["Fc"] = rng.uniform(0.1, 0.4) * f_typ
    if "torque_sensor_offset" in hidden:
        truth["OF"] = rng.choice([-1, 1]) * rng.uniform(0.05, 0.2) * f_typ
    if "time_delay" in hidden:
        truth["tau"] = rng.uniform(3, 15) * 1e-3 if fs >= 1000 else rng.uniform(10, 30) * 1e-3
    dur = rng.uniform(8, 14) if fs >= 1000 else rng.uniform(30, 50)
    return Case(seed=seed, flavour=flavour, fs=fs, duration=float(dur),
                profile=str(rng.choice(["ptp", "chirp"])), rest_fraction=float(rng.uniform(0.2, 0.5)),
                hidden=tuple(hidden), truth=truth, velocity_recorded=bool(rng.random() < 0.4),
                quantum=float(quantum), noise_rel=float(10 ** rng.uniform(-2, np.log10(0.05))),
                ar=float(rng.uniform(0, 0.8)), outlier_rate=float(rng.choice([0.0, 0.002])),
                vmax=float(vmax))


# ----------------------------------------------------------------------------- reference motion

_min_jerk = min_jerk


def reference(case: Case, rng) -> callable:
    """Reference r(t) -> (q, qd, qdd), as a piecewise function of time (moves and rests)."""
    T = case.duration
    segs = []  # (t0, t1, kind, params)
    t, q = 0.5, 0.0
    rest_total = case.rest_fraction * T
    move_total = T - rest_total
    n_moves = max(4, int(move_total / (0.8 if case.profile == "ptp" else 2.5)))
    move_d = move_total / n_moves
    rest_d = rest_total / (n_moves + 1)
    t = rest_d
    for k in range(n_moves):
        if case.profile == "ptp":
            v_peak = case.vmax * rng.uniform(0.2, 1.0)          # several speed levels
            dq = rng.choice([-1, 1]) * v_peak * move_d / 1.875  # min-jerk peak speed = 1.875 dq / T
            if case.flavour == "pendulum" and abs(q + dq) > 1.2:
                dq = -dq
            segs.append((t, t + move_d, "ptp", (q, dq)))
            q += dq
        else:
            amp = case.vmax * rng.uniform(0.3, 1.0)
            f0, f1 = rng.uniform(0.2, 0.5), rng.uniform(1.0, 3.0)
            if case.flavour == "pendulum" and abs(q) > 0.8:
                amp = -amp if np.sign(amp) == np.sign(q) else amp
            segs.append((t, t + move_d, "chirp", (q, amp, f0, f1)))
            q += float(_chirp_pos(np.array([move_d]), amp, f0, (f1 - f0) / move_d, move_d)[0])
        t += move_d + rest_d

    def r(tt):
        tt = np.atleast_1d(np.asarray(tt, float))
        out_q, out_v, out_a = np.zeros_like(tt), np.zeros_like(tt), np.zeros_like(tt)
        for (a, b, kind, p) in segs:
            d = b - a
            inside = (tt >= a) & (tt < b)
            after = tt >= b
            if kind == "ptp":
                q0, dq = p
                s = (tt[inside] - a) / d
                x, xd, xdd = _min_jerk(s)
                out_q[inside], out_v[inside], out_a[inside] = q0 + dq * x, dq * xd / d, dq * xdd / d**2
                out_q[after] = q0 + dq
            else:
                q0, amp, f0, f1 = p
                # velocity = amp * w(s) sin(phase), w a smooth window; position = integral (numeric)
                s = (tt[inside] - a) / d
                w, wd, _ = _min_jerk(np.minimum(s, 1 - s) * 2)  # ramps up to the middle and down
                k = (f1 - f0) / d
                ph = 2 * np.pi * (f0 * (tt[inside] - a) + 0.5 * k * (tt[inside] - a) ** 2)
                fr = f0 + k * (tt[inside] - a)
                v = amp * w * np.sin(ph)
                sgn = np.where(s < 0.5, 1.0, -1.0)
                acc = amp * (wd * 2 * sgn / d * np.sin(ph) + w * 2 * np.pi * fr * np.cos(ph))
                out_v[inside], out_a[inside] = v, acc
                out_q[inside] = q0 + _chirp_pos(tt[inside] - a, amp, f0, k, d)
                out_q[after] = q0 + _chirp_pos(np.array([d]), amp, f0, k, d)[0]
        return out_q, out_v, out_a

    # tabulate once on a fine grid (the ODE right-hand side then only interpolates)
    grid = np.arange(-0.2, case.duration + 0.2, 2e-4)
    tab = r(grid)

    def r_fast(tt):
        tt = np.atleast_1d(np.asarray(tt, float))
        return tuple(np.interp(tt, grid, x) for x in tab)

    return r_fast


def _chirp_pos(tau, amp, f0, k, d, n=4001):
    grid = np.linspace(0, d, n)
    s = grid / d
    w, _, _ = _min_jerk(np.minimum(s, 1 - s) * 2)
    v = amp * w * np.sin(2 * np.pi * (f0 * grid + 0.5 * k * grid**2))
    pos = scipy.integrate.cumulative_trapezoid(v, grid, initial=0.0)
    return np.interp(tau, grid, pos)


# ----------------------------------------------------------------------------- truth simulation

def friction(v, tr: dict):
    """Smooth friction law: Fv v + tanh(v / eps) (Fc + (Fs - Fc) exp(-(v / vs)^2)), N or N m."""
    fs = tr.get("Fs", 0.0) or tr["Fc"]
    return tr["Fv"] * v + np.tanh(v / tr["eps"]) * (tr["Fc"] + (fs - tr["Fc"]) * np.exp(-(v / tr["vs"]) ** 2))


def simulate(case: Case) -> dict:
    """Integrate the closed loop (solve_ivp, LSODA) and produce the recorded signals.

    Returns:
        ``{"t", "q", "qd" (NaN if not recorded), "effort", "q_true", "qd_true", "u_true"}``.
    """
    rng = np.random.default_rng(case.seed + 7919)
    tr = case.truth
    ref = reference(case, rng)
    M, mc = tr["M"], tr["mc"]
    wn = 2 * np.pi * (6.0 if case.flavour != "slew" else 2.0)
    kp, kd = M * wn**2, 2 * 0.8 * M * wn

    def control(t, q, v):
        rq, rv, ra = ref(t)
        return M * ra + kp * (rq - q) + kd * (rv - v) + mc * G * np.sin(rq)

    def rhs(t, x):
        u = control(t, x[0], x[1])[0]
        return [x[1], (u - friction(x[1], tr) - mc * G * np.sin(x[0])) / M]

    n = int(round(case.duration * case.fs))
    t = np.arange(n) / case.fs
    max_step = 0.5 / case.fs if case.fs < 1000 else 1e-3
    sol = scipy.integrate.solve_ivp(rhs, (-0.1, t[-1] + 0.01), [0.0, 0.0], method="LSODA",
                                    dense_output=True, rtol=1e-7, atol=1e-9, max_step=max_step)
    x = sol.sol(t)
    xd = sol.sol(t - tr["tau"])   # the command the effort sensor sees tau later
    u_meas = control(t - tr["tau"], xd[0], xd[1])
    u_true = control(t, x[0], x[1])
    rms = float(np.sqrt(np.mean(u_true**2)))
    sigma = case.noise_rel * rms
    noise = coloured_noise(rng, n, sigma, case.ar, case.outlier_rate)
    effort = u_meas + tr["OF"] + noise
    q = quantize(x[0], case.quantum)
    qd = x[1] + rng.standard_normal(n) * 0.002 * case.vmax if case.velocity_recorded else np.full(n, np.nan)
    return {"t": t, "q": q, "qd": qd, "effort": effort, "q_true": x[0], "qd_true": x[1], "u_true": u_true}


def write_bag(case: Case, path, rec: dict | None = None) -> dict:
    """Simulate (unless ``rec`` is given) and write the case as an MCAP bag
    (``/axis/joint_states`` + ``/plant_description``). Returns the recording."""
    from cablelab.bags import BagWriter

    rec = rec if rec is not None else simulate(case)
    with BagWriter(path, overwrite=True) as w:
        w.write_description(case.description_yaml())
        w.write_joint_states("/axis/joint_states", rec["t"] + 1.0, ["joint"], position=rec["q"][:, None],
                             velocity=rec["qd"][:, None], effort=rec["effort"][:, None])
    return rec
