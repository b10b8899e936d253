"""Foxglove (JSON) and PlotJuggler (XML) layouts of a plant, derived from its topics.

A layout is a list of :class:`Panel` (a title and the series it plots) built from what the
plant declares, never written per plant:

* one panel per output channel: ``/<plant>/model/measured`` against ``/<plant>/model/prediction``
  (the overlay bag of :mod:`cablelab.overlay`, and the live ``model_monitor`` node);
* the residual of every channel (``/<plant>/model/residual``);
* the cable tensions: every contract JointState topic named ``.../cable_tensions``, effort per
  cable;
* estimate against truth: every contract topic ``.../<x>_estimate`` paired with the
  ``.../ground_truth/<y>`` topic of the same type (the one whose name ``<y>`` is part of ``<x>``
  when several fit);
* Foxglove only: a 3D panel on ``/<plant>/markers`` (:mod:`cablelab.markers`) in frame ``world``.

JointState series need the names in the message: the model channels come from the overlay bag
or the plant's ``channels``; the names of other JointState topics from a bag of the plant
(``names``) or the plant's ``topic_names(description)``; a topic whose names are unknown is left
out. Foxglove addresses an element by index (``/t.effort[2]``), PlotJuggler by the ROS 2
parser's series names (``/t/<name>/effort`` for JointState, ``/t/inertia/m`` otherwise).
"""
from __future__ import annotations

import json
from dataclasses import dataclass
from xml.sax.saxutils import quoteattr

JOINT_STATE = "sensor_msgs/msg/JointState"
INERTIA = "geometry_msgs/msg/InertiaStamped"
TOOLS = ("foxglove", "plotjuggler")
COLOURS = ("#1f77b4", "#d62728", "#2ca02c", "#ff7f0e", "#9467bd", "#8c564b", "#e377c2", "#17becf")


@dataclass(frozen=True)
class Series:
    """One plotted number: ``topic``, ``field`` (``effort``, ``position``, ``inertia.m``) and, for
    JointState, the element ``name`` at ``index``."""

    topic: str
    field: str
    name: str | None = None
    index: int | None = None
    label: str = ""

    def foxglove_path(self) -> str:
        return f"{self.topic}.{self.field}" + (f"[{self.index}]" if self.index is not None else "")

    def plotjuggler_name(self) -> str:
        if self.name is not None:
            return f"{self.topic}/{self.name}/{self.field}"
        return f"{self.topic}/{self.field.replace('.', '/')}"


@dataclass(frozen=True)
class Panel:
    title: str
    series: tuple


def _joint_series(topic: str, names, field: str, label: str = "") -> list[Series]:
    return [Series(topic, field, n, i, f"{label}{n}") for i, n in enumerate(names)]


def _pairs(contract: dict) -> list[tuple[str, str]]:
    """(estimate topic, truth topic) pairs: same type, the truth's last name part in the
    estimate's name when several truths fit."""
    out = []
    for est, typ in sorted(contract.items()):
        if not est.endswith("_estimate"):
            continue
        stem = est.rsplit("/", 1)[1][: -len("_estimate")]
        truths = [t for t, ty in sorted(contract.items()) if "/ground_truth/" in t and ty == typ]
        named = [t for t in truths if t.rsplit("/", 1)[1] in stem or stem in t.rsplit("/", 1)[1]]
        pick = named or (truths if len(truths) == 1 else [])
        if pick:
            out.append((est, pick[0]))
    return out


def panels(plant: str, channels, contract: dict, names: dict) -> list[Panel]:
    """The panels of a plant's layout.

    Args:
        plant: plant name (topic prefix ``/<plant>``).
        channels: the model's output channel names.
        contract: the plant's topics, name -> type.
        names: JointState topic -> element names (those known).
    """
    from .overlay import stage_topics

    mt = stage_topics(plant)
    out = [Panel(f"{ch}: measured vs model", (Series(mt["measured"], "effort", ch, c, "measured"),
                                              Series(mt["prediction"], "effort", ch, c, "model")))
           for c, ch in enumerate(channels)]
    out.append(Panel("residual (measured - model)",
                     tuple(_joint_series(mt["residual"], channels, "effort"))))
    for topic, typ in sorted(contract.items()):
        if typ == JOINT_STATE and topic.endswith("/cable_tensions") and names.get(topic):
            out.append(Panel("cable tensions (N)", tuple(_joint_series(topic, names[topic], "effort"))))
    for est, truth in _pairs(contract):
        typ = contract[est]
        if typ == INERTIA:
            for f, what in (("inertia.m", "mass (kg)"), ("inertia.com.x", "x_G (m)"),
                            ("inertia.com.y", "y_G (m)")):
                out.append(Panel(f"{what}: estimate vs truth",
                                 (Series(est, f, label="estimate"), Series(truth, f, label="truth"))))
        elif typ == JOINT_STATE:
            known = names.get(est) or names.get(truth)
            for i, n in enumerate(known or ()):
                out.append(Panel(f"{n}: estimate vs truth", (Series(est, "position", n, i, "estimate"),
                                                             Series(truth, "position", n, i, "truth"))))
    return out


# ------------------------------------------------------------------ Foxglove
def _split(ids: list, direction: str = "column"):
    if len(ids) == 1:
        return ids[0]
    half = (len(ids) + 1) // 2
    other = "row" if direction == "column" else "column"
    return {"first": _split(ids[:half], other), "second": _split(ids[half:], other),
            "direction": direction, "splitPercentage": 100.0 * half / len(ids)}


def foxglove_layout(plant: str, pans: list[Panel]) -> dict:
    """A Foxglove layout (the JSON of *Layouts > Import*): one Plot panel per :class:`Panel`,
    x axis = header stamp, plus a 3D panel on ``/<plant>/markers`` following ``world``."""
    config, ids = {}, []
    for k, p in enumerate(pans):
        pid = f"Plot!{plant}{k}"
        config[pid] = {"title": p.title, "paths": [
            {"value": s.foxglove_path(), "enabled": True, "timestampMethod": "headerStamp",
             "label": s.label or s.foxglove_path(), "color": COLOURS[i % len(COLOURS)]}
            for i, s in enumerate(p.series)],
            "showLegend": True, "legendDisplay": "floating", "showXAxisLabels": True,
            "showYAxisLabels": True, "isSynced": True, "xAxisVal": "timestamp"}
        ids.append(pid)
    tid = f"3D!{plant}"
    config[tid] = {"followTf": "world", "scene": {}, "cameraState": {"distance": 12.0, "perspective": True,
                                                                     "phi": 60.0, "thetaOffset": 45.0},
                   "topics": {f"/{plant}/markers": {"visible": True}}, "layers": {}, "transforms": {}}
    return {"configById": config, "globalVariables": {}, "userNodes": {},
            "playbackConfig": {"speed": 1.0}, "layout": _split([tid] + ids)}


def foxglove_references(doc: dict) -> list[tuple[str, str]]:
    """(topic, field path) of every series a Foxglove layout names (for checks)."""
    out = []
    for cfg in doc["configById"].values():
        for p in cfg.get("paths", ()):
            topic, _, field = p["value"].partition(".")
            out.append((topic, field))
        for topic in cfg.get("topics", {}):
            out.append((topic, ""))
    return out


# ------------------------------------------------------------------ PlotJuggler
def plotjuggler_layout(plant: str, pans: list[Panel]) -> str:
    """A PlotJuggler layout (*Load Layout*): one tab, the panels stacked in two columns."""
    def area(p: Panel) -> str:
        curves = "".join(f'       <curve name={quoteattr(s.plotjuggler_name())} color="{COLOURS[i % len(COLOURS)]}"/>\n'
                         for i, s in enumerate(p.series))
        return (f'     <DockArea name={quoteattr(p.title)}>\n'
                f'      <plot mode="TimeSeries" style="Lines" flip_x="false" flip_y="false">\n'
                f'       <range left="0" right="1" top="1" bottom="0"/>\n       <limitY/>\n'
                f'{curves}      </plot>\n     </DockArea>\n')

    cols = [pans[0::2], pans[1::2]] if len(pans) > 1 else [pans]

    def column(ps) -> str:
        sizes = ";".join(f"{1.0 / len(ps):.6f}" for _ in ps)
        return (f'    <DockSplitter orientation="-" count="{len(ps)}" sizes="{sizes}">\n'
                + "".join(area(p) for p in ps) + '    </DockSplitter>\n')

    body = "".join(column(c) for c in cols if c)
    ncol = sum(1 for c in cols if c)
    return ("<?xml version='1.0' encoding='UTF-8'?>\n<root>\n"
            ' <tabbed_widget parent="main_window" name="Main Window">\n'
            f'  <Tab containers="1" tab_name={quoteattr(plant)}>\n   <Container>\n'
            f'   <DockSplitter orientation="|" count="{ncol}" sizes="{";".join(f"{1.0 / ncol:.6f}" for _ in range(ncol))}">\n'
            f'{body}   </DockSplitter>\n   </Container>\n  </Tab>\n'
            '  <currentTabIndex index="0"/>\n </tabbed_widget>\n'
            ' <use_relative_time_offset enabled="0"/>\n</root>\n')


def plotjuggler_references(xml_text: str) -> list[str]:
    """Curve names of a PlotJuggler layout (for checks)."""
    import xml.etree.ElementTree as ET

    return [c.get("name") for c in ET.fromstring(xml_text).iter("curve")]


# ------------------------------------------------------------------ from a plant
def shipped_layout(plant: str, tool: str):
    """Path of the layout shipped in the repository's ``layouts/`` (``<plant>.foxglove.json``,
    ``<plant>.plotjuggler.xml``; ``cablelab layout`` writes the same)."""
    from pathlib import Path

    ext = "foxglove.json" if tool == "foxglove" else "plotjuggler.xml"
    return Path(__file__).resolve().parents[3] / "layouts" / f"{plant}.{ext}"



def names_from_bag(bag) -> dict:
    """JointState topic -> the element names of its first message (a bag of the plant)."""
    out = {}
    for topic, typ in bag.topics.items():
        if typ == JOINT_STATE and bag.counts.get(topic):
            out[topic] = list(bag.joint_state(topic).names)
    return out


def plant_layout(plant_name: str, tool: str, *, bag=None, description=None) -> str:
    """The layout file's text (JSON or XML) of a plant: channels and names from ``bag`` (an
    overlay bag or any recording of the plant) when given, else from the plant's declarations."""
    from .errors import CablelabError
    from .overlay import model_namespace
    from .registry import get_plant
    from .topics import plant_topics

    if tool not in TOOLS:
        raise CablelabError(f"--tool {tool!r}: expected one of {', '.join(TOOLS)}")
    plant = get_plant(plant_name)
    contract = dict(plant_topics(plant_name))
    names = {}
    if bag is not None and description is None:
        description = bag.description
    if plant.topic_names is not None:
        names.update(plant.topic_names(description))
    channels = tuple(plant.channels)
    if bag is not None:
        names.update(names_from_bag(bag))
        stages = f"{model_namespace(plant_name)}/stages"
        if bag.has(stages):
            channels = tuple(json.loads(bag.strings(stages)[-1])["channels"])
    if not channels:
        raise CablelabError(f"plant {plant_name}: no output channels known; give --bag with an overlay "
                            f"bag (cablelab compare BAG --out BAG2)")
    pans = panels(plant_name, channels, contract, names)
    if tool == "foxglove":
        return json.dumps(foxglove_layout(plant_name, pans), indent=1) + "\n"
    return plotjuggler_layout(plant_name, pans)


__all__ = ["Panel", "Series", "TOOLS", "shipped_layout", "foxglove_layout", "foxglove_references", "names_from_bag",
           "panels", "plant_layout", "plotjuggler_layout", "plotjuggler_references"]
