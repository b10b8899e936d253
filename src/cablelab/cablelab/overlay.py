"""Model overlay bags: the model's prediction and residual beside the measurement, as topics.

``cablelab compare BAG --out BAG2`` and ``cablelab diagnose BAG --greedy --out BAG2`` write a
copy of the input bag's topics plus, per model *stage*, three sensor_msgs/JointState topics whose
names are the plant's output channels (``ds.channels``) and whose ``effort`` holds the channel's
value at the conditioned sample times (header stamp = log time = the input's stamp time):

* ``/<plant>/model/<stage>/measured``: the measured channel the model is fitted to;
* ``/<plant>/model/<stage>/prediction``: the identified model's output;
* ``/<plant>/model/<stage>/residual``: measured - prediction (NaN where a sample is not used).

``compare`` writes one stage, the compared model, under ``/<plant>/model/{measured,prediction,
residual}`` (no stage level); ``diagnose --greedy`` writes the nominal model as stage
``nominal``, the model after each added effect as ``plus_<effect id>``, and the final model
under the stage-less names too, so a layout names one set of topics for both verbs.
``/<plant>/model/stages`` (std_msgs/String, transient local) holds JSON: per stage its name,
topic namespace, effects and identified parameters. Foxglove and PlotJuggler then show
measurement, model and residual on the input's time axis.

Everything here is ROS-free; the bag is written by :class:`~cablelab.bags.BagWriter`.
"""
from __future__ import annotations

import json
from dataclasses import dataclass, field

import numpy as np

from .bags import DESCRIPTION_TOPIC, BagWriter
from .dataset import Dataset
from .model import Model

#: the kinds of per-stage topics and what each holds
KINDS = ("measured", "prediction", "residual")


def model_namespace(plant: str, stage: str | None = None) -> str:
    """``/<plant>/model`` or ``/<plant>/model/<stage>``."""
    return f"/{plant}/model" + (f"/{stage}" if stage else "")


def stage_topics(plant: str, stage: str | None = None) -> dict[str, str]:
    """kind -> topic of one stage (``stage`` None: the stage-less final/compared model)."""
    ns = model_namespace(plant, stage)
    return {k: f"{ns}/{k}" for k in KINDS}


def stage_name(added: str | None) -> str:
    """Stage of a greedy step: ``nominal`` first, then ``plus_<effect id>``."""
    return "nominal" if added is None else f"plus_{added}"


@dataclass
class Stage:
    """One model's overlay: channel values (N, C) at the dataset's sample times ``t``."""

    name: str | None
    effects: list
    t: np.ndarray
    channels: tuple
    measured: np.ndarray
    prediction: np.ndarray
    params: dict = field(default_factory=dict)

    @property
    def residual(self) -> np.ndarray:
        return self.measured - self.prediction


def stage_from_fit(name: str | None, ds: Dataset, ident) -> Stage:
    """A :class:`Stage` from an :class:`~cablelab.fit.identification.Identification` on ``ds``:
    measured = the fitted measurement (NaN where not valid), prediction = the model output."""
    valid = np.asarray(ident.valid, dtype=bool)
    measured = np.where(valid[:, None], ident.residual + ident.y_hat, np.nan)
    return Stage(name, list(ident.model.effects), np.asarray(ds.t, dtype=float), tuple(ds.channels),
                 measured, np.asarray(ident.y_hat, dtype=float),
                 {k: float(v) for k, v in ident.params.items()})


def fit_stage(name: str | None, ds: Dataset, model: Model) -> Stage:
    """Fit ``model`` on the whole record and make its stage."""
    from .fit import identify

    return stage_from_fit(name, ds, identify(model, ds))


def copy_topics(writer: BagWriter, bag) -> list[str]:
    """Copy every message of ``bag`` (same log times, same bytes) into ``writer``; returns the
    topics left out because their message type is unknown to the typestore (one line each)."""
    from . import cdr

    known = cdr.typestore().fielddefs
    skipped = []
    for topic, msgtype in sorted(bag.topics.items()):
        if msgtype not in known:
            skipped.append(f"{topic}: message type {msgtype} unknown, not copied to the overlay bag")
            continue
        writer.add_topic(topic, msgtype, transient_local=topic == DESCRIPTION_TOPIC)
        times, raws = bag.raw(topic)
        for t_ns, data in zip(np.asarray(times).tolist(), raws):
            writer.write_raw(topic, t_ns, data)
    return skipped


def write_stage(writer: BagWriter, plant: str, stage: Stage, namespace_stage: str | None) -> None:
    """The three JointState topics of one stage (under ``namespace_stage``: a stage name or None)."""
    topics = stage_topics(plant, namespace_stage)
    values = {"measured": stage.measured, "prediction": stage.prediction, "residual": stage.residual}
    for kind, topic in topics.items():
        writer.write_joint_states(topic, stage.t, list(stage.channels), effort=values[kind])


def write_overlay(path, bag, plant: str, stages: list[Stage], *, final: Stage | None = None,
                  markers=None) -> list[str]:
    """Write the overlay bag at ``path`` (a new bag directory; the caller makes it atomic):
    the input's topics, each stage under its name, ``final`` (default: the last stage) under the
    stage-less names, ``/<plant>/model/stages``, and optionally ``markers`` ``(t, arrays)`` of
    :mod:`cablelab.markers` on ``/<plant>/markers``. Returns warning lines (topics not copied)."""
    final = final if final is not None else stages[-1]
    with BagWriter(path) as w:
        warnings = copy_topics(w, bag)
        doc = []
        for st in stages:
            if st.name is not None:
                write_stage(w, plant, st, st.name)
            doc.append({"stage": st.name, "namespace": model_namespace(plant, st.name),
                        "effects": st.effects, "params": st.params})
        write_stage(w, plant, final, None)
        if final.name is not None:
            doc.append({"stage": None, "namespace": model_namespace(plant), "same_as": final.name,
                        "effects": final.effects, "params": final.params})
        t0 = float(final.t[0]) if len(final.t) else 0.0
        w.write_strings(f"{model_namespace(plant)}/stages", [t0],
                        [json.dumps({"channels": list(final.channels), "stages": doc})],
                        transient_local=True)
        if markers is not None:
            from .markers import write_markers

            write_markers(w, f"/{plant}/markers", *markers)
    return warnings


__all__ = ["KINDS", "Stage", "copy_topics", "fit_stage", "model_namespace", "stage_from_fit",
           "stage_name", "stage_topics", "write_overlay", "write_stage"]
