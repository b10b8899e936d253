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
        warnings: one line each (time base, NaN samples, negative tensions, recovered bag).
    """

    reports: dict = field(default_factory=dict)
    warnings: list = field(default_factory=list)

    @property
    def gaps(self) -> list:
        return [g for r in self.reports.values() for g in r.gaps]

    def mask(self, t, margin: float) -> np.ndarray:
        """(N,) bool: samples at ``t`` outside every gap (widened by ``margin`` s)."""
        return gap_mask(t, self.gaps, margin)


def _expected_names(plant: str, desc) -> dict[str, tuple[str, ...]]:
    """topic -> the joint names the description implies (exact set for the CDPR)."""
    if plant == "cdpr" and getattr(desc, "cdpr", None) is not None:
        n = len(desc.cdpr.cables)
        return {"/cdpr/joint_states": tuple(f"winch_{i}" for i in range(1, n + 1)),
                "/cdpr/cable_tensions": tuple(f"cable_{i}" for i in range(1, n + 1))}
    if plant == "crane":
        return {"/crane/joint_states": ("slew", "luff", "hoist")}
    return {}


def _topics(plant: str, bag, required) -> list[tuple[str, str]]:
    out = list(required)
    if plant == "cdpr":
        for extra in ("/cdpr/cable_tensions", "/cdpr/reference", "/cdpr/platform_pose"):
            if bag.has(extra) and all(extra != t for t, _ in out):
                out.append((extra, bag.topics[extra]))
    return out


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


def check_bag(bag, plant, desc, options: dict | None = None, limits: Limits = Limits()) -> BagCheck:
    """Check the topics ``plant`` reads from ``bag`` against ``desc``.

    Raises:
        CablelabError: no section for the plant in the description; stamps going back in time;
            joint or cable names that do not match the description (one line naming the bag,
            topic and both counts).
    """
    options = options or {}
    out = BagCheck()
    if getattr(desc, plant.name, "absent") is None:     # e.g. "axis: null" parses to no section
        raise CablelabError(f"{bag.path}: plant description for plant {plant.name} has no '{plant.name}' "
                            f"section (key {plant.name}: is missing or empty)")
    if getattr(bag, "recovered", False):
        out.warnings.append(f"{bag.path}: unfinished bag (recorder killed?), read up to its last "
                            f"complete chunk")
    names_wanted = _expected_names(plant.name, desc)
    for topic, msgtype in _topics(plant.name, bag, plant.topics):
        if not bag.has(topic) or bag.counts.get(topic, 0) == 0:
            continue
        got = _stamps_and_values(bag, topic, msgtype)
        if got is None:
            continue
        t, t_log, vals, series = got
        want = names_wanted.get(topic)
        if want is not None:
            _check_names(bag, topic, series, want, plant.name, desc)
        rep: TimebaseReport = check_stamps(t, t_log, topic=topic, values=vals, limits=limits)
        raise_if_impossible(rep, str(bag.path))
        out.reports[topic] = rep
        out.warnings.extend(rep.warnings())
        if topic == "/cdpr/cable_tensions" and (options.get("tensions") or "dynamometer") == "dynamometer":
            out.warnings.extend(negative_tension_warnings(series.effort, series.names, topic))
    return out


def _check_names(bag, topic, series, want, plant, desc) -> None:
    have = list(series.names)
    if plant == "cdpr":
        if set(have) != set(want):
            noun = "cables" if "tensions" in topic else "winches"
            raise CablelabError(
                f"{bag.path}: {topic} has {len(have)} {noun} ({_span(have)}) but the plant "
                f"description has {len(want)} cables; give the description of this robot (--description)")
    else:
        missing = [n for n in want if n not in have]
        if missing:
            raise CablelabError(f"{bag.path}: {topic} has joints {', '.join(have) or 'none'}; the {plant} "
                                f"description needs {', '.join(want)} (missing {', '.join(missing)})")


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
    for j in np.flatnonzero(count):
        name = names[j] if j < len(names) else f"column {j + 1}"
        out.append(f"{topic}: {name} has {int(count[j])} of {T.shape[0]} samples with negative tension "
                   f"(min {np.nanmin(T[:, j]):.4g} N): cables cannot push, check the sensor sign and offset")
    return out
