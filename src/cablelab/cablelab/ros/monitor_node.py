"""``model_monitor --plant P``: the plant's identified model on the live topics (any plant).

A thin adapter over :class:`cablelab.monitor.ResidualMonitor`: the plant's input topics (those
its workbench dataset reads) are taken as serialised messages (no per-message decoding), the
window is evaluated on a timer, and for every new sample ``/<plant>/model/{measured,prediction,
residual}`` (sensor_msgs/JointState, names = the output channels, ``effort`` = the value,
stamped like the inputs) is published, the same topics as the overlay bag of ``cablelab compare
--out``. /diagnostics is OK while every channel's residual stays in its band, WARN (ERROR beyond
``error_factor`` bands) with the channel, the residual's size and the stamps when one stays
outside longer than ``hold`` s; published at once when the level changes.

ROS parameters: :data:`PARAMETERS`, and the plant's own options its dataset takes
(:func:`plant_parameters`, e.g. the CDPR's ``tensions``), together :func:`parameters_for`
(``model_monitor --plant P --help``). The monitor is off every critical path: run it with a
positive niceness beside a 1 kHz loop.
"""
from __future__ import annotations

import dataclasses
import importlib
import time
from pathlib import Path

import numpy as np
from sensor_msgs.msg import JointState

from ..errors import CablelabError
from ..plant_interface import cli_options
from . import convert
from .params import DESCRIPTION, Param, executor_params, help_text, merge
from .plant_node import PlantNode
from .qos import publisher_qos, stream_qos

PARAMETERS = merge((
    Param("identify_json", "", "file written by `cablelab identify BAG --json` (the model's effects, "
          "parameters and residual RMS per channel); empty = identify the description's nominal "
          "model on the first `calibrate` s of the stream"),
    DESCRIPTION,
    Param("band_sigma", 4.0, "band = this x the residual RMS of each channel", gt=0.0, le=1e6),
    Param("hold", 0.5, "time outside the band before an alarm (and inside before it clears)", "s",
          gt=0.0, le=3600.0),
    Param("window", 3.0, "stream conditioned per evaluation", "s", gt=0.0, le=3600.0),
    Param("period", 0.25, "wall time between evaluations", "s wall", gt=0.0, le=3600.0),
    Param("calibrate", 10.0, "stream used to fit the nominal model when no identify_json is given", "s",
          gt=0.0, le=1e6),
    Param("error_factor", 3.0, "ERROR instead of WARN beyond this many bands", gt=0.0, le=1e6),
), executor_params(False))

#: the verb whose options the monitor takes: it compares the model with the stream as it does
MONITOR_VERB = "compare"


def plant_parameters(plant) -> tuple:
    """The plant's own options its dataset takes (the fields of its ``options_type`` that
    ``cablelab compare`` offers on the command line, :func:`cablelab.plant_interface.option`) as
    ROS parameters of the same name, default, choices and help (CDPR: ``tensions``)."""
    if plant.options_type is None:
        return ()
    defaults = {f.name: f.default for f in dataclasses.fields(plant.options_type)}
    return tuple(Param(name, defaults[name], f"{plant.name}: {opt.help}", choices=tuple(opt.choices or ()))
                 for name, opt in cli_options(plant.options_type) if MONITOR_VERB in opt.verbs)


def parameters_for(plant_name: str) -> tuple:
    """Every ROS parameter of ``model_monitor --plant plant_name``: :data:`PARAMETERS` and the
    plant's own (:func:`plant_parameters`)."""
    from ..registry import get_plant

    return merge(PARAMETERS, plant_parameters(get_plant(plant_name)))


def _msg_class(msgtype: str):
    pkg, _, name = msgtype.partition("/msg/")
    return getattr(importlib.import_module(f"{pkg}.msg"), name)


class ModelMonitorNode(PlantNode):
    def __init__(self, plant: str):
        super().__init__("model_monitor")
        from ..monitor import MonitorModel
        from ..registry import get_plant

        self.plant_name = plant
        self.plant = get_plant(plant)
        v = self.declare_params(parameters_for(plant))
        self.options = {p.name: getattr(v, p.name) for p in plant_parameters(self.plant)}
        self.band_sigma, self.hold, self.window = v.band_sigma, v.hold, v.window
        self.period, self.calibrate, self.error_factor = v.period, v.calibrate, v.error_factor
        path = v.identify_json
        if path:
            try:
                text = Path(path).read_text()
            except OSError as exc:
                raise CablelabError(f"model_monitor: parameter identify_json: {path}: {exc.strerror}") from None
            self.spec = MonitorModel.from_identify_json(text, self.band_sigma, path)
        else:
            self.spec = MonitorModel(())
        self.monitor = None
        self.use_fast_executor(False)
        q = stream_qos()
        self.pubs = {k: self.create_publisher(JointState, f"/{plant}/model/{k}", publisher_qos())
                     for k in ("measured", "prediction", "residual")}
        self.listen_for_description(v.description)
        from ..monitor import ResidualMonitor

        topics = ResidualMonitor.input_topics(self.plant)
        required = {t for t, _ in self.plant.topics}
        for topic, msgtype in topics.items():
            self.inputs.add(topic, timeout=max(2.0, 4 * self.period), required=topic in required)
            self.create_subscription(_msg_class(msgtype), topic,
                                     lambda data, topic=topic: self.on_message(topic, data), q, raw=True)
        self.level = 0
        self.start_diagnostics()
        self.create_timer(self.period, self.evaluate)

    def set_description(self, desc) -> None:
        from ..monitor import ResidualMonitor

        if desc.plant != self.plant_name:
            self.description_problem = f"/plant_description is a {desc.plant} plant, not {self.plant_name}"
            return
        super().set_description(desc)
        self.keep_first_description = True
        self.monitor = ResidualMonitor(self.plant_name, desc, self.spec, window=self.window, hold=self.hold,
                                       band_sigma=self.band_sigma, calibrate=self.calibrate,
                                       error_factor=self.error_factor, options=self.options)

    def on_message(self, topic: str, data: bytes) -> None:
        now = time.monotonic()
        if self.monitor is not None and self.monitor.add(topic, data):
            self.inputs.accept(topic, np.ones(1), now)
        else:
            self.inputs.accept(topic, None, now)

    def evaluate(self) -> None:
        if self.monitor is None:
            return
        was = self.monitor.calibrated
        s = self.monitor.step()
        if self.monitor.calibrated and not was:
            self.get_logger().info("model " + " + ".join(self.monitor.model.effects) + ", band " + ", ".join(
                f"{ch} +-{b:.4g}" for ch, b in zip(self.monitor.channels, self.monitor.check.band)))
        if s is None:
            return
        names = list(s.channels)
        res = s.residual
        for i, t in enumerate(s.t.tolist()):
            for kind, vals in (("measured", s.measured), ("prediction", s.prediction), ("residual", res)):
                self.pubs[kind].publish(convert.joint_state_msg(t, names, None, None, vals[i]))
        for a in s.raised:
            self.get_logger().warning(a.line())
        level = self.monitor.check.level()
        if level != self.level:
            self.level = level
            self.diag.publish()

    def extend_status(self, level, msg, values):
        if self.monitor is None:
            return max(level, 1), "waiting for /plant_description" if msg == "ok" else msg, values
        mlevel, mmsg, mvalues = self.monitor.status()
        values.update(mvalues)
        text = mmsg if msg == "ok" else f"{msg}; {mmsg}"
        return max(level, mlevel), text, values


def make_node(plant: str) -> PlantNode:
    return ModelMonitorNode(plant)


def main(argv=None) -> int:
    """``model_monitor --plant P [--ros-args ...]``."""
    import argparse
    import sys

    from ..registry import available_plants
    from .runner import run_node, split_ros_args

    argv = list(sys.argv[1:] if argv is None else argv)
    user, ros_args = split_ros_args(argv)
    pre = argparse.ArgumentParser(add_help=False)
    pre.add_argument("--plant", choices=available_plants())
    known, _ = pre.parse_known_args(user)
    specs = parameters_for(known.plant) if known.plant else PARAMETERS   # with P: P's own options too
    parser = argparse.ArgumentParser(
        prog="model_monitor", description="Live model monitor: the plant's identified model on the live "
        "topics; publishes /<plant>/model/{measured,prediction,residual} and raises WARN/ERROR on "
        "/diagnostics when a channel's residual leaves its band for longer than a set time.",
        formatter_class=argparse.RawDescriptionHelpFormatter,
        epilog="ROS parameters (--ros-args -p name:=value, or --params-file FILE.yaml):\n"
               f"{help_text(specs)}\n\nStops cleanly on SIGINT/SIGTERM.")
    parser.add_argument("--plant", choices=available_plants(), required=True, help="which plant")
    args = parser.parse_args(user)
    return run_node(lambda: make_node(args.plant), ros_args, "model_monitor")
