"""Leg measurements as a workbench :class:`~cablelab.model.Dataset` (inverse model, hybrid-aware).

The leg's equations (003 eq. 1, 23, 24) are linear in the parameters once the known forces are
moved to one side. With s = contact (1 stance), f = 1 - s:

    y = s (F_in + k (z_0 - z))                                   (known: eq. 3, measured k)
      = m (zdd + g) + d_s s zdot + d_f f zdot - F_0 s + ...       (effects)
        + sum_events m (1 - beta) zdot^- delta(t - t_e)           (impact map, eq. 24)

The velocity jump of eq. 24 is an impulse in the measured acceleration; its regressor is the
event's pre-impact velocity as a step, passed through the same filter and derivative as the
height (exact by linearity). Every signal (y and all regressor bases) goes through the same
zero-phase low-pass ("parallel filtering"), so the switched terms and the impulses are smeared
identically on both sides. Regimes: phase (stance / flight) and time to the nearest transition.
"""
from __future__ import annotations

import numpy as np

from ...conditioning import derivatives, lowpass
from ...errors import CablelabError
from ...model import Dataset
from .description import leg_of
from .identify import start_state
from .strides import phase_runs

#: default zero-phase low-pass of the inverse model (4th order): far above the 3 Hz stance
#: dynamics, low enough to tame the double derivative of a 0.09 mm encoder
CUTOFF_HZ, ORDER = 40.0, 4
#: samples dropped at both record ends (filter transients)
EDGE = 60


def event_steps(t: np.ndarray, z: np.ndarray, contact: np.ndarray) -> dict[str, np.ndarray]:
    """Step series ``sum_e zdot^-_e 1[t >= t_e]`` of touch-downs and lift-offs (m/s); the
    pre-impact velocity comes from a polynomial fit of z just before each contact edge."""
    steps = {"touchdown": np.zeros_like(z), "liftoff": np.zeros_like(z)}
    for a, _, ph in phase_runs(contact)[1:]:
        if a < 8:
            continue
        _, v = start_state(t, z, a - 1, 12, 2, forward=False)
        steps["touchdown" if ph == 1 else "liftoff"][a:] += v
    return steps


def dataset_from_arrays(t, z, contact, tau, description, options: dict | None = None,
                        source: str = "data") -> Dataset:
    """Leg dataset from raw 1 kHz arrays: t (s), z (m), contact (0/1), tau (N m)."""
    options = options or {}
    leg = leg_of(description)
    p = leg.params(description.gravity)
    t, z, tau = (np.asarray(x, float) for x in (t, z, tau))
    if contact is None:
        raise CablelabError(f"{source}: the leg dataset needs the phase (contact switch or estimated)")
    s = (np.asarray(contact, float) > 0.5).astype(float)
    fs = 1.0 / float(np.median(np.diff(t)))
    cut = float(options.get("cutoff_hz", CUTOFF_HZ))
    L = lambda x: lowpass(x, fs, cut, ORDER)  # noqa: E731
    _, zd, zdd = derivatives(z, fs, cut, ORDER)
    zd_raw = np.gradient(z, 1.0 / fs)
    f_in = s * tau / np.sqrt(np.maximum(4 * p.L**2 - z * z, 1e-12))
    e = p.spring_rest - z
    y = L(s * (f_in + p.k * e))
    ev = event_steps(t, z, s.astype(int))
    imp = {k: np.gradient(L(v), 1.0 / fs) for k, v in ev.items()}
    signals = {
        "acc": zdd + description.gravity, "zd_stance": L(zd_raw * s), "zd_flight": L(zd_raw * (1 - s)),
        "stance": L(s), "flight": L(1 - s), "e2": L(p.k * e**2 * s), "e3": L(p.k * e**3 * s),
        "sign": L(np.sign(zd)), "acc_flight": (zdd + description.gravity) * (1 - s),
        "impulse_td": imp["touchdown"], "impulse_lo": imp["liftoff"], "z": z, "zd": zd, "contact": s,
        "f_in": f_in,
    }
    valid = np.zeros(len(t), bool)
    valid[EDGE:-EDGE] = True
    # time to the nearest transition, for residuals aligned to touch-down / lift-off
    edges = np.flatnonzero(np.diff(s) != 0) + 1
    dist = np.min(np.abs(np.arange(len(t))[:, None] - edges[None, :]), axis=1) / fs if len(edges) else np.full(len(t), np.inf)
    near = np.where(dist < 0.02, "within 20 ms of a transition", "away from transitions")
    return Dataset(plant="leg", t=t, y=y[:, None], channels=("body",), units=("N",), signals=signals,
                   actuators=("body",), act_vel=zd[:, None], act_units=(("N", "m"),), valid=valid,
                   regimes={"phase": np.where(s > 0.5, "stance", "flight"), "transition": near},
                   inputs={"velocity": zd}, description=description, source=source)


def check_bag(bag, description, options, series) -> list[str]:
    """Input checks before a fit (:func:`cablelab.bagcheck.check_bag`): say when the phase has
    to come from the height because the bag has no contact switch."""
    if bag.has("/leg/contact"):
        return []
    return [f"{bag.path}: no /leg/contact in the bag; phase detected from the height "
            "(z < z_td - 0.5 mm, 20 ms dwell)"]


def dataset(bag, description, options: dict | None = None) -> Dataset:
    """Leg dataset from a bag's ``/leg/joint_states`` (joint ``body`` height, ``motor`` torque) and
    ``/leg/contact``. Without the contact topic the phase comes from the height (live estimator
    rule) and :func:`check_bag` says so."""
    from .estimator import estimate_series

    js = bag.joint_state("/leg/joint_states")
    if "body" not in js.names:
        raise CablelabError(f"{bag.path}: /leg/joint_states has no joint 'body' (has {js.names})")
    z = js.position[:, js.names.index("body")]
    tau = js.effort[:, js.names.index("motor")] if "motor" in js.names else np.zeros_like(z)
    tau = np.nan_to_num(tau)
    contact = None
    if bag.has("/leg/contact"):
        c = bag.joint_state("/leg/contact")
        contact = np.interp(js.t, c.t, c.position[:, 0]) > 0.5
    if contact is None:       # (said as a warning of the input checks: check_bag below)
        leg = leg_of(description)
        contact = estimate_series(js.t, z, None, tau, leg.params(description.gravity))["phase"]
    return dataset_from_arrays(js.t, z, contact, tau, description, options, source=str(bag.path))
