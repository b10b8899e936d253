"""Single- and double-pendulum baselines (000 sec. 6, Fig. 11-12; spec sec. 3.2, *proposed*:
the paper does not define them).

* ``single``: point mass on a massless rod of length ``l`` from S, spherical (hinges x then y),
  viscous damping ``c`` per axis, no yaw. Output = the point at distance L along the rod (the
  lower attachment point) so it is comparable with the platform pose.
* ``double``: massless rod of length L from S (spherical, damping ``c1``), then the platform and
  frozen arms as one rigid body (mass M, CoM depth ``c_p``, inertia from the parameter set) on a
  spherical joint at the rod end (damping ``c2``), no virtual PD: it tilts freely; no yaw.

Neither has arm-platform coupling: arm motion in the data is a disturbance they cannot produce.
Fitted with :func:`cablelab.fit.simulation.fit_simulation` (``nmse``) on
:func:`mujoco.rollout.rollout`, like the virtual-joint model.
"""
from __future__ import annotations

import mujoco
import numpy as np

from ...fit.simulation import fit_simulation
from ...effects.base import Param
from .identify import Experiment, _stack
from .params import VirtualParams
from .reference import planar_bodies
from .sim import initial_state, simulate
from .swing import swing_from_pose

__all__ = ["baseline_xml", "fit_baseline", "simulate_baseline", "BASELINES"]

BASELINES = ("single", "double")


def _f(x) -> str:
    return " ".join(repr(float(v)) for v in np.atleast_1d(x))


def baseline_xml(kind: str, p: VirtualParams, values: dict, timestep: float = 1e-3) -> str:
    """MJCF of a baseline with parameters ``values`` (single: l, c; double: c1, c2)."""
    b = planar_bodies(p)
    M, cp, I = b["M_B"], b["c_B"], b["I_B"]
    S = _f(p.S)
    head = (f'<mujoco><compiler angle="radian"/><option timestep="{timestep!r}" '
            f'integrator="implicitfast" gravity="0 0 -9.81"/><worldbody>')
    if kind == "single":
        l, c = float(values.get("l", p.L + cp)), float(values.get("c", 0.1))
        tiny = 1e-6 * M
        body = (f'<body name="rod" pos="{S}"><joint name="sx" axis="1 0 0" damping="{c!r}"/>'
                f'<joint name="sy" axis="0 1 0" damping="{c!r}"/>'
                f'<inertial pos="0 0 {-l!r}" mass="{M!r}" diaginertia="{tiny!r} {tiny!r} {tiny!r}"/>'
                f'<site name="platform" pos="0 0 {-p.L!r}"/></body>')
    elif kind == "double":
        c1, c2 = float(values.get("c1", 0.1)), float(values.get("c2", 0.01))
        tiny = 1e-6
        body = (f'<body name="rod" pos="{S}"><joint name="sx" axis="1 0 0" damping="{c1!r}"/>'
                f'<joint name="sy" axis="0 1 0" damping="{c1!r}"/>'
                f'<inertial pos="0 0 {-p.L / 2!r}" mass="{tiny!r}" diaginertia="{tiny!r} {tiny!r} {tiny!r}"/>'
                f'<body name="plat" pos="0 0 {-p.L!r}"><joint name="px" axis="1 0 0" damping="{c2!r}"/>'
                f'<joint name="py" axis="0 1 0" damping="{c2!r}"/>'
                f'<inertial pos="0 0 {-cp!r}" mass="{M!r}" diaginertia="{I!r} {I!r} {I!r}"/>'
                f'<site name="platform"/></body></body>')
    else:
        from ...errors import CablelabError
        raise CablelabError(f"suspended baseline {kind!r}: expected one of {', '.join(BASELINES)}")
    return (head + body + '</worldbody><sensor><framepos objtype="site" objname="platform"/>'
            '<framequat objtype="site" objname="platform"/></sensor></mujoco>')


def _params(kind: str, p: VirtualParams) -> list[Param]:
    cp = planar_bodies(p)["c_B"]
    if kind == "single":
        return [Param("l", "m", p.L + cp, 0.3 * p.L, 3.0 * p.L, "rod length to the point mass"),
                Param("c", "N m s/rad", 0.1, 0.0, 10.0, "viscous damping per axis")]
    return [Param("c1", "N m s/rad", 0.1, 0.0, 10.0, "rod damping"),
            Param("c2", "N m s/rad", 0.01, 0.0, 1.0, "platform joint damping")]


def simulate_baseline(kind: str, p: VirtualParams, exps: list[Experiment], value_sets: list[dict]):
    """Outputs ``[set][experiment] -> (N, 3)`` [r_x, r_y, yaw (= 0)] of a baseline."""
    rest = np.array(p.S, float) - [0, 0, p.L]
    out = [[None] * len(exps) for _ in value_sets]
    for d in sorted({e.duration for e in exps}):
        idx = [i for i, e in enumerate(exps) if e.duration == d]
        models, x0s = [], []
        for v in value_sets:
            m = mujoco.MjModel.from_xml_string(baseline_xml(kind, p, v))
            for i in idx:
                q0 = exps[i].q0
                start = {"sx": q0.get("J8", 0.0), "sy": q0.get("J9", 0.0)}
                models.append(m)
                x0s.append(initial_state(m, start))
        runs = simulate(models, np.array(x0s), d)
        k = 0
        for s in range(len(value_sets)):
            for i in idx:
                r, e = runs[k], exps[i].every
                k += 1
                sw = swing_from_pose(r.pos[e - 1::e], r.quat[e - 1::e], p.S, rest_pos=rest, rest_yaw=0.0)
                y = np.stack([sw["r_x"], sw["r_y"], 0 * sw["yaw"]], 1)
                out[s][i] = y[:len(exps[i].t)]
    return out


def fit_baseline(kind: str, p: VirtualParams, exps: list[Experiment], *, max_iter: int = 20):
    """NMSE fit of a baseline to the experiments' r_x, r_y (yaw left out: the baselines have
    none). Returns ``(values, outputs per experiment)``."""
    import dataclasses
    pos_only = [dataclasses.replace(e, use=e.use & np.array([True, True, False])) for e in exps]
    y_meas = _stack(pos_only, [e.y for e in pos_only])

    def sim(value_sets):
        outs = simulate_baseline(kind, p, pos_only, value_sets)
        return np.stack([_stack(pos_only, o) for o in outs])

    fit = fit_simulation(sim, _params(kind, p), y_meas, objective="nmse", max_iter=max_iter)
    return fit.params, simulate_baseline(kind, p, exps, [fit.params])[0]
