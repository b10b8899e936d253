"""The hopping-leg plant (003): its nominal model, the effects a diagnosis tries, and the
:class:`Plant` record the registry holds."""
from __future__ import annotations

from ...registry import Plant
from . import effects
from .dataset import check_bag, dataset
from .description import parse_section

JOINT_STATE = "sensor_msgs/msg/JointState"


def baseline(description) -> tuple[str, ...]:
    """Nominal model: the leg's inertia with stance and flight damping (spec 003 sec. 7)."""
    return effects.BASELINE


def candidates(description) -> tuple[str, ...]:
    """Effects a leg diagnosis tries (spec 003 sec. 7)."""
    return effects.BASELINE + effects.CANDIDATES


PLANT = Plant(
    name="leg",
    topics=(("/leg/joint_states", JOINT_STATE),),
    dataset=dataset,
    baseline=baseline,
    candidates=candidates,
    parse_section=parse_section,
    contract_topics={                          # CONTRACT sec. 2, spec 003_leg.md sec. 5
        "/leg/joint_states": JOINT_STATE,
        "/leg/contact": JOINT_STATE,
        "/leg/reference": "trajectory_msgs/msg/JointTrajectory",
        "/leg/effort_commands": "std_msgs/msg/Float64MultiArray",
        "/leg/hop_estimate": JOINT_STATE,
        "/leg/ground_truth/state": JOINT_STATE,
    },
    joint_topic="/leg/joint_states",
    joints=("body", "motor"),
    checked_topics=("/leg/contact",),
    check_bag=check_bag,
    channels=("body",),
    topic_names=lambda desc: {"/leg/joint_states": ["body", "motor"], "/leg/contact": ["contact"],
                              **{t: ["height", "phase", "apex_height", "grf"] for t in
                                 ("/leg/hop_estimate", "/leg/ground_truth/state")}},
)
