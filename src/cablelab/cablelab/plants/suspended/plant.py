"""The suspended dual-arm platform plant (000): its nominal model, the effects a diagnosis tries,
and the :class:`Plant` record the registry holds."""
from __future__ import annotations

from ...registry import Plant, lazy_hook
from . import effects, topics
from .dataset import CHANNELS as _CHANNELS, dataset
from .description import parse_section


def baseline(description) -> tuple[str, ...]:
    """Nominal model: compound-pendulum swing + viscous cable-joint friction (spec sec. 7; the
    arm coupling joins only on data with arm motion, see :mod:`.effects`)."""
    return effects.BASELINE


def candidates(description) -> tuple[str, ...]:
    """Spec sec. 7 candidates; ``platform_levelling`` only where the nominal swing model's level
    platform is the variant's own (LiCAS, target -q8/-q9). CRANEbot's platform follows the cable
    (target 0): there the tilt relative to the cable absorbs the reduced model's platform-rotation
    inertia and would be called on nominal data (README, "Platform levelling")."""
    sec = getattr(description, "suspended", None)
    if sec is not None and not sec.params().level_to_swing:
        return tuple(c for c in effects.CANDIDATES if c != "platform_levelling")
    return effects.CANDIDATES


PLANT = Plant(
    name="suspended",
    topics=((topics.PLATFORM_POSE, topics.POSE),),
    dataset=dataset,
    baseline=baseline,
    candidates=candidates,
    parse_section=parse_section,
    contract_topics=topics.TYPES,              # CONTRACT sec. 2, spec 000_suspended.md sec. 5
    channels=_CHANNELS,
    topic_names=lambda desc: {t: ["swing_x", "swing_y", "yaw", "r_x", "r_y"] for t in
                              (topics.SWING_ESTIMATE, topics.GROUND_TRUTH_SWING)},
    markers=lazy_hook(f"{__package__}.markers", "bag_markers"),
)
