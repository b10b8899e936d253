"""Checks of a bag against its plant description before anything is fitted: the time base of
every topic the plant reads (:mod:`cablelab.timebase`), joint / cable names against the
description, cables that push (negative tension).

:func:`check_bag` returns a :class:`BagCheck` (the per-topic time-base reports, the gaps, warning
lines) or raises a one-line :class:`~cablelab.errors.CablelabError` for impossible input:
stamps that go back in time, a description with another number of cables or other joints than
the bag.
"""
from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

from .errors import CablelabError
from .timebase import Limits, TimebaseReport, check_stamps, gap_mask, raise_if_impossible

from .bags.series import JOINT_STATE, MULTIDOF_TRAJECTORY as MULTIDOF, POSE_STAMPED


@dataclass
class BagCheck:
    """Result of :func:`check_bag`.

    Attributes:
        reports: topic -> :class:`~cablelab.timebase.TimebaseReport`.
        warnings: one line each (time base, NaN samples, negative tensions, recovered bag,
            measured velocities that contradict their positions).
        derived_velocity: topic -> joint names whose measured velocity contradicts the
            derivative of their position (:func:`velocity_checks`): the plants' datasets derive
            those velocities from the positions instead (``DatasetOptions.derived_velocity``).
    """

    reports: dict = field(default_factory=dict)
    warnings: list = field(default_factory=list)
    derived_velocity: dict = field(default_factory=dict)

    @property
    def gaps(self) -> list:
        return [g for r in self.reports.values() for g in r.gaps]

    def mask(self, t, margin: float) -> np.ndarray:
        """(N,) bool: samples at ``t`` outside every gap (widened by ``margin`` s)."""
        return gap_mask(t, self.gaps, margin)


def _stamps_and_values(bag, topic: str, msgtype: str):
    """(header stamps, log times, values) of a topic, or None for a type without a header."""
    if msgtype == JOINT_STATE:
        s = bag.joint_state(topic)
        cols = [a for a in (s.position, s.effort) if a.size and np.isfinite(a).any()]
        vals = np.concatenate(cols, axis=1) if cols else None
        return s.t, s.t_receive, vals, s
    if msgtype == POSE_STAMPED:
        s = bag.pose(topic)
        return s.t, s.t_receive, s.position, s
    if msgtype == MULTIDOF:
        s = bag.multidof_trajectory(topic)
        return s.t, s.t_receive, s.position, s
    return None


def check_bag(bag, plant, desc, options=None, limits: Limits = Limits()) -> BagCheck:
    """Check the topics ``plant`` reads from ``bag`` against ``desc``.

    Raises:
        CablelabError: no section for the plant in the description; stamps going back in time;
            joint or cable names that do not match the description (one line naming the bag,
            topic and both counts).
    """
    from .plant_interface import DatasetOptions

    options = DatasetOptions.build(plant, options)   # a DatasetOptions, or a mapping of its fields
    out = BagCheck()
    if getattr(desc, plant.name, "absent") is None:     # e.g. "axis: null" parses to no section
        raise CablelabError(f"{bag.path}: plant description for plant {plant.name} has no '{plant.name}' "
                            f"section (key {plant.name}: is missing or empty)")
    out.warnings.extend(getattr(bag, "warnings", ()))    # damaged chunks, missing split files
    if getattr(bag, "recovered", False) and not getattr(bag, "warnings", ()):
        out.warnings.append(f"{bag.path}: unfinished bag (recorder killed?), read up to its last "
                            f"complete chunk")
    checked = list(plant.topics) + [(t, bag.topics[t]) for t in plant.checked_topics
                                    if bag.has(t) and all(t != r for r, _ in plant.topics)]
    series_by_topic = {}
    for topic, msgtype in checked:
        if not bag.has(topic) or bag.counts.get(topic, 0) == 0:
            continue
        got = _stamps_and_values(bag, topic, msgtype)
        if got is None:
            continue
        t, t_log, vals, series = got
        series_by_topic[topic] = series
        rep: TimebaseReport = check_stamps(t, t_log, topic=topic, values=vals, limits=limits)
        raise_if_impossible(rep, str(bag.path))
        out.reports[topic] = rep
        out.warnings.extend(rep.warnings())
        if msgtype == JOINT_STATE:
            bad, lines = velocity_checks(series, topic)
            if bad:
                out.derived_velocity[topic] = bad
                out.warnings.extend(lines)
    if plant.check_bag is not None:     # the plant's own checks: names vs description, values
        out.warnings.extend(plant.check_bag(bag, desc, options, series_by_topic))
    return out


def velocity_checks(series, topic: str) -> tuple[list[str], list[str]]:
    """Measured velocities that contradict the derivative of their positions (sign flipped,
    other units, unrelated): ``(joint names, warning lines)``. The verbs then use the velocity
    derived from the position for those joints (:func:`cablelab.velocity.velocity_agreement`)."""
    from .velocity import velocity_agreement, velocity_contradiction

    vel, pos = getattr(series, "velocity", None), getattr(series, "position", None)
    if vel is None or pos is None or vel.size == 0 or not np.isfinite(vel).any():
        return [], []
    bad, lines = [], []
    for j, name in enumerate(series.names[:min(vel.shape[1], pos.shape[1])]):
        ag = velocity_agreement(series.t, pos[:, j], vel[:, j])
        what = velocity_contradiction(ag)
        if what:
            bad.append(name)
            lines.append(f"{topic}: {name}: the measured velocity contradicts the derivative of the "
                         f"position ({what}; scale {ag['scale']:.3g}, correlation "
                         f"{ag['correlation']:.2f} on {ag['samples']} moving samples); NOT USED, the "
                         f"velocity derived from the position is used instead (fix the velocity's "
                         f"sign or units in the recording, or leave it empty)")
    return bad, lines


def check_names(bag, topic: str, names, want, *, exact: bool = False, plant: str = "",
                noun: str = "joints", described: str = "") -> None:
    """One-line error when the names of ``topic`` do not match what the description implies.

    Args:
        names: the names in the bag; want: the names the description implies.
        exact: the sets must be equal (e.g. one name per cable), else ``want`` must be present.
        noun: what the names are (``winches``, ``cables``); described: what the description
            counts (default ``noun``).
    """
    have = list(names)
    if exact:
        if set(have) != set(want) or len(have) != len(set(have)):
            missing = [n for n in want if n not in have]
            extra = [n for n in dict.fromkeys(have) if n not in want]
            dup = [n for n in dict.fromkeys(have) if have.count(n) > 1]
            if len(set(have)) != len(want):
                what = (f"{len(set(have))} {noun} ({_span(have)}) but the plant description has "
                        f"{len(want)} {described or noun}")
            else:   # same count, other names: say which
                what = (f"{len(have)} {noun}, as many as the plant description, but named "
                        f"{_span(have)}, not {_span(want)}")
            parts = ([f"missing {_list(missing)}"] if missing else []) + \
                ([f"unexpected {_list(extra)}"] if extra else []) + \
                ([f"repeated {_list(dup)}"] if dup else [])
            raise CablelabError(
                f"{bag.path}: {topic} has {what} ({'; '.join(parts)}); give the description of "
                f"this robot (--description) or name the {noun} {_span(want)}")
        return
    missing = [n for n in want if n not in have]
    if missing:
        raise CablelabError(f"{bag.path}: {topic} has {noun} {', '.join(have) or 'none'}; the {plant} "
                            f"description needs {', '.join(want)} (missing {', '.join(missing)})")


def _list(names, most: int = 4) -> str:
    names = list(names)
    return ", ".join(names[:most]) + (f" and {len(names) - most} more" if len(names) > most else "")


def _span(names) -> str:
    return names[0] if len(names) == 1 else (f"{names[0]}..{names[-1]}" if names else "none")


def negative_tension_warnings(tensions, names, topic: str) -> list[str]:
    """Cables cannot push: one warning line per cable with negative tension samples."""
    T = np.asarray(tensions, dtype=float)
    if T.ndim != 2 or T.size == 0:
        return []
    with np.errstate(invalid="ignore"):
        neg = T < 0
    count = neg.sum(axis=0)
    out = []
    bad = np.flatnonzero(count)
    if bad.size > 3:    # one line for many cables (a sign convention, not a sensor)
        names_bad = [names[j] if j < len(names) else f"column {j + 1}" for j in bad]
        return [f"{topic}: {bad.size} cables ({_list(names_bad)}) have negative tension in "
                f"{int(neg.any(axis=1).sum())} of {T.shape[0]} samples (min {np.nanmin(T):.4g} N): "
                f"cables cannot push, check the sensor sign and offset"]
    for j in bad:
        name = names[j] if j < len(names) else f"column {j + 1}"
        out.append(f"{topic}: {name} has {int(count[j])} of {T.shape[0]} samples with negative tension "
                   f"(min {np.nanmin(T[:, j]):.4g} N): cables cannot push, check the sensor sign and offset")
    return out
