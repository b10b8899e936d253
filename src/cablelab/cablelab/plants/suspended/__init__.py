"""Plant ``suspended``: cable-suspended dual-arm platforms LiCAS and CRANEbot (paper 000,
spec 000_suspended.md, issue 11). One package per plant:

* :mod:`.params` - parameter sets ``repo`` (default) and ``table5`` per variant, defects D1-D8;
* :mod:`.description` - the ``suspended:`` description section;
* :mod:`.mjcf` - virtual-joint MuJoCo chain J7-J12 with virtual PD, and the truth plants;
* :mod:`.sim` - rollout-based simulation; :mod:`.reference` - planar solve_ivp reference;
* :mod:`.swing` - swing/yaw estimate from the platform pose (batch + live);
* :mod:`.controller` - arm PD + gravity under the platform attitude, Fig. 7, sway damping;
* :mod:`.identify` - Pearson (000 eq. 3-7) and NMSE identification on mujoco.minimize/rollout;
* :mod:`.dataset`, :mod:`.effects` - the workbench plug-in (compare / diagnose / report);
* :mod:`.bag` - writing simulated runs as contract bags.
"""
from __future__ import annotations

from ...registry import Plant, register_plant
from . import effects as _effects  # noqa: F401  (registers the effect ids)
from . import topics
from .dataset import CHANNELS as _CHANNELS, dataset
from .description import parse_section

__all__ = ["SUSPENDED"]


def baseline(description) -> tuple[str, ...]:
    """Nominal model: compound-pendulum swing + viscous cable-joint friction (spec sec. 7; the
    arm coupling joins only on data with arm motion, see :mod:`.effects`)."""
    return _effects.BASELINE


def candidates(description) -> tuple[str, ...]:
    """Spec sec. 7 candidates; ``platform_levelling`` only where the nominal swing model's level
    platform is the variant's own (LiCAS, target -q8/-q9). CRANEbot's platform follows the cable
    (target 0): there the tilt relative to the cable absorbs the reduced model's platform-rotation
    inertia and would be called on nominal data (README, "Platform levelling")."""
    sec = getattr(description, "suspended", None)
    if sec is not None and not sec.params().level_to_swing:
        return tuple(c for c in _effects.CANDIDATES if c != "platform_levelling")
    return _effects.CANDIDATES


SUSPENDED = register_plant(Plant(
    name="suspended",
    topics=((topics.PLATFORM_POSE, topics.POSE),),
    dataset=dataset,
    baseline=baseline,
    candidates=candidates,
    channels_doc="swing_x, swing_y, yaw: modal inertia x angular acceleration (N m)",
    section=parse_section,
    contract_topics=topics.TYPES,              # CONTRACT sec. 2, spec 000_suspended.md sec. 5
    channels=_CHANNELS,
    topic_names=lambda desc: {t: ["swing_x", "swing_y", "yaw", "r_x", "r_y"] for t in
                              (topics.SWING_ESTIMATE, topics.GROUND_TRUTH_SWING)},
    markers=lambda bag, desc: _bag_markers(bag, desc),
))


def _bag_markers(bag, desc):
    from .markers import bag_markers

    return bag_markers(bag, desc)

PLANT = SUSPENDED
