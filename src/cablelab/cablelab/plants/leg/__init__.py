"""Plant ``leg``: the parallel-elastic hopping leg of paper 003 (spec 003_leg.md).

Modules: :mod:`.hybrid` (phase model, guards, impact maps), :mod:`.sim` (MuJoCo plant with
event-located switches), :mod:`.reference` (scipy oracle for tests), :mod:`.estimator`,
:mod:`.controller`, :mod:`.identify` (staged NMSE identification, k-fold CV), :mod:`.effects`,
:mod:`.dataset` (workbench inverse model), :mod:`.description` (``leg:`` section).
"""
from __future__ import annotations

from ...registry import Plant, register_plant
from . import effects as _effects  # noqa: F401  (registers the leg effects)
from .dataset import check_bag, dataset
from .description import parse_section

JOINT_STATE = "sensor_msgs/msg/JointState"


def _baseline(description) -> tuple[str, ...]:
    return _effects.BASELINE


def _candidates(description) -> tuple[str, ...]:
    return _effects.BASELINE + _effects.CANDIDATES


LEG = register_plant(Plant(
    name="leg",
    topics=(("/leg/joint_states", JOINT_STATE),),
    dataset=dataset,
    baseline=_baseline,
    candidates=_candidates,
    channels_doc="body: s (F_in + k (z_0 - z)), the known vertical force on the body (N)",
    section=parse_section,
    contract_topics={                          # CONTRACT sec. 2, spec 003_leg.md sec. 5
        "/leg/joint_states": JOINT_STATE,
        "/leg/contact": JOINT_STATE,
        "/leg/reference": "trajectory_msgs/msg/JointTrajectory",
        "/leg/effort_commands": "std_msgs/msg/Float64MultiArray",
        "/leg/hop_estimate": JOINT_STATE,
        "/leg/ground_truth/state": JOINT_STATE,
        "/leg/markers": "visualization_msgs/msg/MarkerArray",
    },
    joint_topic="/leg/joint_states",
    joints=("body", "motor"),
    checked_topics=("/leg/contact",),
    check_bag=check_bag,
    channels=("body",),
    topic_names=lambda desc: {"/leg/joint_states": ["body", "motor"], "/leg/contact": ["contact"],
                              **{t: ["height", "phase", "apex_height", "grf"] for t in
                                 ("/leg/hop_estimate", "/leg/ground_truth/state")}},
    markers=lambda bag, desc: _bag_markers(bag, desc),
))


def _bag_markers(bag, desc):
    from .markers import bag_markers

    return bag_markers(bag, desc)

PLANT = LEG
