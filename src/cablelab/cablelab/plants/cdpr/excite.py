"""Experiment design for the CDPR (``cablelab excite``): the platform's position (level
platform, 001 assumption 1) follows the designed Fourier series inside a box of the workspace
where every cable stays taut and below its maximum tension, and the dataset the CDPR effects see
for such a motion.

The box (:func:`excite_limits`): centred between the exit points, first a share of the footprint
the platform's anchors can cover inside the exit points' (x, y) and a share of the exit points'
height (z), then shrunk until the tensions of the controller's feedforward
distribution (001 eq. 14 nearest the preload, :func:`.control.feedforward_tensions`) stay
between :data:`MIN_TENSION` and the drives' maximum (``max_torque`` R/r) on a grid of the box,
for the empty platform and for it with :data:`PAYLOAD_FACTOR` times its mass, at every
acceleration up to the box's limit along each axis (corners of the acceleration box). The
designed reference is checked against the same tensions sample by sample (the
:class:`~cablelab.excite.Limits` constraint). It starts where ``cable_sim_node --plant cdpr``
starts, at point A of the pick-and-place (:func:`start_position`), and moves from there to the
box's centre before the Fourier series (:func:`cablelab.excite.lead_in`).
"""
from __future__ import annotations

import dataclasses
import itertools

import numpy as np

from ...excite import Exciter, Limits
from .control import PdffConfig, feedforward_tensions, motor_rates
from .dataset import CdprArrays, dataset_from_arrays
from .geometry import cable_geometry
from .topics import REFERENCE
from .trajectory import pick_and_place

JOINTS = ("x", "y", "z")
#: lowest tension a designed motion may ask of a cable, N (the controller floors at
#: PdffConfig.min_tension; the margin covers tracking error and the unknown payload)
MIN_TENSION = 2.0 * PdffConfig().min_tension
#: the box must hold from the empty platform up to this multiple of its mass
PAYLOAD_FACTOR = 2.0
#: speed (m/s) and acceleration (m/s^2) limits of the platform per axis
SPEED = (0.3, 0.3, 0.2)
ACCEL = (0.4, 0.4, 0.3)
#: first box: share of the half-span the platform's anchors can travel inside the exit points'
#: footprint (the exit points' half-span minus the anchors'), around the exit points' centre, and
#: the z range as shares of the exit points' height. Offsets seen through W(p) separate from the
#: weight only as far as the platform travels (the internal-force part of the offsets shows
#: through the change of W's null space, first order in the displacement)
SPAN_SHARE = 0.8
Z_SHARE = (0.2, 0.5)


def _max_tension(c) -> float:
    return PdffConfig().max_torque * c.gear_ratio / c.drum_radius


def tension_range(c, gravity, position, acceleration, mass) -> tuple[np.ndarray, np.ndarray]:
    """(min, max) over the cables per sample of the feedforward tensions (N) at positions (N, 3)
    with accelerations (N, 3) for a moving mass (kg), level platform, Model II of the
    description."""
    geom = cable_geometry(c.exit_points, c.anchor_points, position, None, c.pulley_radius,
                          c.swivel_axes)
    t = feedforward_tensions(geom, mass, acceleration, gravity, preload=PdffConfig().preload,
                             min_tension=-np.inf)
    return t.min(axis=1), t.max(axis=1)


def _tension_violations(c, gravity, q, qdd) -> list[str]:
    m0 = c.platform_mass or 366.0
    out = []
    for m in (m0, PAYLOAD_FACTOR * m0):
        lo, hi = tension_range(c, gravity, q, qdd, m)
        if lo.min() < MIN_TENSION:
            k = int(np.argmin(lo))
            out.append(f"cable tension {lo[k]:.4g} N below {MIN_TENSION:g} N at {np.round(q[k], 3).tolist()} "
                       f"with {m:g} kg (slack)")
        if hi.max() > _max_tension(c):
            k = int(np.argmax(hi))
            out.append(f"cable tension {hi[k]:.4g} N above {_max_tension(c):.4g} N at "
                       f"{np.round(q[k], 3).tolist()} with {m:g} kg")
    return out


def excite_limits(description) -> Limits:
    """The workspace box (module doc) where every cable stays taut, with the speed and
    acceleration limits."""
    c, g = description.cdpr, description.gravity
    A = np.asarray(c.exit_points, float)
    B = np.asarray(c.anchor_points, float)
    centre = 0.5 * (A.min(axis=0) + A.max(axis=0))
    half = SPAN_SHARE * np.maximum(0.5 * np.ptp(A, axis=0) - np.abs(B).max(axis=0), 0.05)
    ztop = A[:, 2].min()
    lo = np.array([centre[0] - half[0], centre[1] - half[1], Z_SHARE[0] * ztop])
    hi = np.array([centre[0] + half[0], centre[1] + half[1], Z_SHARE[1] * ztop])
    acc = np.array(ACCEL)
    corners = np.array(list(itertools.product(*[(-a, 0.0, a) for a in acc])))
    for _ in range(30):
        grid = np.stack(np.meshgrid(*[np.linspace(lo[i], hi[i], 5) for i in range(3)]), -1).reshape(-1, 3)
        q = np.repeat(grid, len(corners), axis=0)
        qdd = np.tile(corners, (len(grid), 1))
        if not _tension_violations(c, g, q, qdd):
            break
        mid, half3 = 0.5 * (lo + hi), 0.5 * (hi - lo)
        lo, hi = mid - 0.85 * half3, mid + 0.85 * half3
    else:
        from ...errors import CablelabError

        raise CablelabError("cdpr: no box of the workspace keeps every cable taut at the design's "
                            "accelerations (check the description's exit and anchor points)")

    def constraint(q, qd, qdd):
        return _tension_violations(c, g, q, qdd)

    return Limits(JOINTS, lo, hi, np.array(SPEED), acc, constraint)


def motion_dataset(t, q, qd, qdd, description):
    """The CDPR dataset (dynamometer wrench channels) of a level platform following the motion
    exactly, the cables carrying the empty platform's feedforward tensions (what the pulley and
    offset columns are evaluated with)."""
    c = description.cdpr
    geom = cable_geometry(c.exit_points, c.anchor_points, q, None, c.pulley_radius, c.swivel_axes)
    tens = feedforward_tensions(geom, c.platform_mass or 366.0, qdd, description.gravity,
                                preload=PdffConfig().preload)
    rates = motor_rates(geom, qd, c.drum_radius, c.gear_ratio)
    n = tens.shape[1]
    arr = CdprArrays(t=np.asarray(t, float), tensions=tens, motor_velocity=rates,
                     motor_effort=np.full((len(t), n), np.nan), position=np.asarray(q, float), R=None,
                     acc=np.asarray(qdd, float), velocity=np.asarray(qd, float), truth_mass=None,
                     truth_com=None, source="dynamometer", scale=c.gear_ratio / c.drum_radius)
    return dataset_from_arrays(arr, description, "designed motion")


def start_position(description=None) -> np.ndarray:
    """Where the platform rests when a designed reference starts: the simulator's start, point A
    of the pick-and-place test trajectory (001 sec. II-C), m."""
    return pick_and_place(np.array([0.0])).position[0]


def _family(params) -> dict:
    """A delay shows through the tensions' change within tau (the platform's jerk): a design
    naming ``tau`` keeps a 20 s base period with five harmonics (up to 0.25 Hz); the others use
    :data:`EXCITER`'s slow, wide family."""
    return {"base_hz": 0.05, "harmonics": 5} if "tau" in params else {}


def loaded(description, values):
    """The description whose platform carries the moving mass ``values["m"]`` a recording's fit
    found (the designed motion's feedforward tensions are that load's; unchanged without a
    positive finite ``m``)."""
    m = values.get("m")
    if m is None or not np.isfinite(m) or m <= 0:
        return description
    return description.with_section("cdpr", dataclasses.replace(description.cdpr, platform_mass=float(m)))


#: the CDPR's experiment design (``cablelab excite``), registered by the package. Base period
#: 60 s, six harmonics (up to 0.1 Hz): the speed limit caps a harmonic's amplitude at v / omega,
#: so a 20 s base period (0.95 m at 0.3 m/s) could not cross the box; the offsets' internal-force
#: part shows through the change of W's null space, so the condition number of (offsets, m, mx,
#: my) falls steeply with the travel
EXCITER = Exciter(limits=excite_limits, motion_dataset=motion_dataset, reference_topic=REFERENCE,
                  base_hz=1 / 60, harmonics=6, trajectory="pose", start=start_position, tune=_family,
                  loaded=loaded)
