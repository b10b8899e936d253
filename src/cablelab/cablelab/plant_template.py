"""The plant template: the files of a new plant package, as ``cablelab new-plant NAME`` writes them.

Every plant, built in or installed through the ``cablelab.plants`` entry-point group, has the
same parts in the same places (docs/architecture.md, "The plant template"). The skeleton written
here is a working plant: a hinge of inertia ``I`` driven by a chirp torque (:mod:`.control`),
simulated in MuJoCo, with the nominal model ``tau = I qdd`` and the generic joint effects
(friction, offset, delay) as candidates, nodes for the three roles, and a test file whose tests
check it against closed forms and through ``cablelab diagnose``. A new plant replaces the law
file by file and keeps the layout.

:func:`write_plant` is the ROS-free core of the verb (:mod:`cablelab.commands.new_plant`).
"""
from __future__ import annotations

import keyword
import re
from pathlib import Path

from .errors import CablelabError

__all__ = ["FILES", "plant_files", "write_plant", "check_name"]

# Tokens replaced in every file: NAME (plant id), CLASS (CamelCase), PACKAGE (import name).
FILES: dict[str, str] = {}

FILES["pyproject.toml"] = '''\
# The NAME plant for cablelab: installed (pip install -e .), it is found through the
# cablelab.plants entry-point group; nothing in cablelab names it.
[build-system]
requires = ["setuptools>=61"]
build-backend = "setuptools.build_meta"

[project]
name = "NAME-plant"
version = "0.1.0"
description = "The NAME plant for cablelab"
requires-python = ">=3.11"
dependencies = ["cablelab"]

[project.entry-points."cablelab.plants"]
NAME = "PACKAGE"

[tool.setuptools]
packages = ["PACKAGE", "PACKAGE.nodes"]

[tool.setuptools.package-data]
PACKAGE = ["README.md", "data/*.yaml"]
'''

FILES["PACKAGE/__init__.py"] = '''\
"""Plant ``NAME``: a hinge of inertia I driven at its joint (replace with what the machine is).

The one registration place: registers :data:`.plant.PLANT` and, by importing :mod:`.effects`,
the plant's effects. Found through the ``cablelab.plants`` entry-point group (pyproject.toml:
``NAME = "PACKAGE"``); nothing else may register.
"""
from __future__ import annotations

from cablelab.registry import register_plant

from . import effects  # noqa: F401  (registers the plant's effects)
from .plant import PLANT

register_plant(PLANT)
'''

FILES["PACKAGE/plant.py"] = '''\
"""The ``NAME`` plant as the workbench sees it: :data:`PLANT`, its hooks (dataset, nominal
model, candidate effects, description section) and what a recording of it holds. Registered by
the package's ``__init__.py``."""
from __future__ import annotations

from cablelab.registry import Plant

from . import effects, topics
from .dataset import dataset
from .description import dump_section, parse_section
from .mjcf import JOINT


def baseline(description) -> tuple[str, ...]:
    """Effect ids of the nominal model (:data:`.effects.NOMINAL`)."""
    return effects.NOMINAL


def candidates(description) -> tuple[str, ...]:
    """Effect ids ``diagnose`` may add; the generic joint effects apply because the plant declares
    the capability ``joint_actuators``."""
    return ("joint_viscous_friction", "joint_coulomb_friction", "torque_sensor_offset")


PLANT = Plant(
    name="NAME",
    topics=((topics.JOINT_STATES, topics.JOINT_STATE),),
    dataset=dataset,
    baseline=baseline,
    candidates=candidates,
    parse_section=parse_section,
    dump_section=dump_section,
    contract_topics=topics.TYPES,
    joint_topic=topics.JOINT_STATES,
    joints=(JOINT,),
    capabilities=frozenset({"joint_actuators"}),
    channels=(JOINT,),
)
'''

FILES["PACKAGE/description.py"] = '''\
"""The ``NAME:`` section of a plant description: parsed and validated with cablelab's public
field validators (one-line errors naming the key path), dumped back as a mapping."""
from __future__ import annotations

import dataclasses
from dataclasses import dataclass

from cablelab.fields import check_keys, mapping, number


@dataclass(frozen=True)
class CLASSDescription:
    """``NAME:`` section. inertia: of the moving body about the hinge, kg m^2."""

    inertia: float


def parse_section(obj) -> CLASSDescription:
    """The validated section (``obj``: the YAML mapping under ``NAME:``)."""
    obj = mapping(obj, "NAME")
    check_keys(obj, "NAME", ("inertia",), ())
    return CLASSDescription(number(obj, "inertia", "NAME", positive=True))


def dump_section(section: CLASSDescription) -> dict:
    """The section as the mapping :func:`parse_section` reads."""
    return dataclasses.asdict(section)
'''

FILES["PACKAGE/dataset.py"] = '''\
"""Bag -> :class:`cablelab.dataset.Dataset`: the hinge's conditioned motion and torque, the
output channel the effects' regressors explain (``tau``, N m)."""
from __future__ import annotations

from cablelab.conditioning import condition_motion
from cablelab.dataset import Dataset
from cablelab.errors import CablelabError
from cablelab.plant_interface import DatasetOptions

from . import topics
from .mjcf import JOINT


def dataset(bag, description, options: DatasetOptions) -> Dataset:
    """The dataset of a recording (``options``: conditioning and the plant's own options)."""
    bag.require(topics.JOINT_STATES, topics.JOINT_STATE)
    js = bag.joint_state(topics.JOINT_STATES)
    if js.names != [JOINT]:
        raise CablelabError(f"{bag.path}: {topics.JOINT_STATES} has joints {js.names}; expected [{JOINT!r}]")
    c = condition_motion(js.t, js.position[:, 0], js.effort[:, 0], options.conditioning, revolute=True,
                         qd=js.velocity[:, 0], source=str(bag.path))
    qd = c["qd"].reshape(-1)
    return Dataset(plant="NAME", t=c["t"], y=c["effort"].reshape(-1, 1), channels=(JOINT,),
                   units=("N m",), signals={"q": c["q"].reshape(-1), "qdd": c["qdd"].reshape(-1)},
                   actuators=(JOINT,), act_vel=qd[:, None], act_units=(("N m", "rad"),),
                   inputs={"velocity": qd}, description=description, source=str(bag.path))
'''

FILES["PACKAGE/effects.py"] = '''\
"""The plant's own effects (regressors of the inverse model ``tau = sum_k theta_k phi_k``),
registered by id; the generic joint effects (friction, offset, delay) come with cablelab."""
from __future__ import annotations

import numpy as np

from cablelab.effects import register
from cablelab.effects.base import Effect, Param

#: the effect ids of the nominal model (the plant's ``baseline``)
NOMINAL = ("NAME_inertia",)

register(Effect(
    id="NAME_inertia", plants=("NAME",),
    params=(Param("I", "kg m^2", 0.0, 0.0, np.inf, "inertia about the hinge"),),
    explanation="torque to accelerate the body about the hinge (I qdd)",
    signature="residual follows the acceleration", reference="plant template",
    regressor=lambda ds: ds.require_signal("qdd").reshape(ds.n, 1, 1)))
'''

FILES["PACKAGE/control.py"] = '''\
"""Control laws of the plant (ROS-free, vectorised over time): the excitation the simulator and
the controller node drive the hinge with."""
from __future__ import annotations

import numpy as np


def chirp(t, duration: float, amplitude: float = 0.3, f0: float = 0.2, f1: float = 2.0):
    """Torque (N m) of a linear chirp from ``f0`` to ``f1`` Hz over ``duration`` s at time(s) ``t``."""
    t = np.asarray(t, dtype=float)
    rate = (f1 - f0) / max(duration, 1e-9)
    return amplitude * np.sin(2 * np.pi * (f0 * t + 0.5 * rate * t * t))
'''

FILES["PACKAGE/mjcf.py"] = '''\
"""The MuJoCo model of the plant: :func:`build_mjcf` (MJCF text) and the name of its joint."""
from __future__ import annotations

JOINT = "hinge"   #: the joint's name in the model and on the joint-state topic


def build_mjcf(section, damping: float = 0.0, timestep: float = 0.001) -> str:
    """A hinge about world y carrying one body of the section's inertia, torque-driven;
    ``damping`` (N m s/rad) is the simulated truth the nominal model lacks."""
    i = section.inertia
    return f"""<mujoco><option timestep="{timestep!r}" integrator="implicitfast" gravity="0 0 -9.81"/>
  <worldbody><body><joint name="{JOINT}" type="hinge" axis="0 -1 0" damping="{damping!r}"/>
    <inertial pos="0 0 0" mass="1" diaginertia="{i!r} {i!r} {i!r}"/></body></worldbody>
  <actuator><motor joint="{JOINT}" name="tau"/></actuator></mujoco>"""
'''

FILES["PACKAGE/sim.py"] = '''\
"""The ROS-free simulator: :class:`CLASSSim` steps the MuJoCo model (:mod:`.mjcf`) under a
held torque; :func:`simulate` runs it under a torque law and :func:`write_bag` records a run as a
contract bag (what the simulator node publishes), for tests and offline data."""
from __future__ import annotations

import mujoco
import numpy as np

from . import topics
from .mjcf import JOINT, build_mjcf


class CLASSSim:
    """The plant of description section ``section`` with hinge ``damping`` (N m s/rad)."""

    def __init__(self, section, damping: float = 0.0, timestep: float = 0.001):
        self.model = mujoco.MjModel.from_xml_string(build_mjcf(section, damping, timestep))
        self.data = mujoco.MjData(self.model)

    @property
    def t(self) -> float:
        return float(self.data.time)

    def state(self) -> tuple[float, float, float]:
        """(t s, q rad, qd rad/s)."""
        return self.t, float(self.data.qpos[0]), float(self.data.qvel[0])

    def advance(self, tau: float, dt: float) -> None:
        """Hold torque ``tau`` (N m) for ``dt`` s."""
        self.data.ctrl[0] = tau
        for _ in range(max(1, int(round(dt / self.model.opt.timestep)))):
            mujoco.mj_step(self.model, self.data)


def simulate(section, duration: float, rate: float, torque, damping: float = 0.0) -> dict:
    """Arrays ``t, q, qd, tau`` sampled at ``rate`` Hz for ``duration`` s under ``torque(t)``,
    held over each period; the torque reported with a sample is the one held over the period
    ending there (as the simulator node publishes it; 0 with the first sample)."""
    sim = CLASSSim(section, damping)
    n = int(round(duration * rate)) + 1
    out = np.empty((n, 4))
    out[0] = (*sim.state(), 0.0)
    for i in range(1, n):
        tau = float(torque(sim.t))
        sim.advance(tau, 1.0 / rate)
        out[i] = (*sim.state(), tau)
    return dict(zip(("t", "q", "qd", "tau"), out.T))


def write_bag(path, run: dict, description_yaml: str, *, torque_noise: float = 0.0, seed: int = 0,
              overwrite: bool = False) -> None:
    """Write a :func:`simulate` run as a bag: the joint states (measured torque with white noise
    of ``torque_noise`` N m), /clock and /plant_description."""
    from cablelab.bags import BagWriter

    noise = np.random.default_rng(seed).normal(0.0, torque_noise, run["t"].size) if torque_noise else 0.0
    with BagWriter(path, overwrite=overwrite) as w:
        w.write_description(description_yaml)
        w.write_clock(run["t"])
        w.write_joint_states(topics.JOINT_STATES, run["t"], [JOINT], position=run["q"][:, None],
                             velocity=run["qd"][:, None], effort=(run["tau"] + noise)[:, None])
'''

FILES["PACKAGE/topics.py"] = '''\
"""The plant's topic names, defined once: the nodes, the registration, the dataset and the bag
writer import them from here."""
from __future__ import annotations

JOINT_STATE = "sensor_msgs/msg/JointState"

JOINT_STATES = "/NAME/joint_states"            # the hinge: angle, rate, applied torque
EFFORT_COMMANDS = "/NAME/effort_commands"      # torque command (the controller node)
PARAMETER_ESTIMATE = "/NAME/parameter_estimate"    # live inertia estimate (the estimator node)

#: topic -> message type of every topic a recording holds
TYPES = {
    JOINT_STATES: JOINT_STATE,
    EFFORT_COMMANDS: "std_msgs/msg/Float64MultiArray",
    PARAMETER_ESTIMATE: "std_msgs/msg/Float64MultiArray",
}
'''

FILES["PACKAGE/demo.py"] = '''\
"""The plant's part of ``./run demo``: set :data:`DEMO` to a :class:`cablelab.demo.DemoPart`
(record: the DDS runs; analyse: the table rows and pages) to join the demo; None: no part."""
from __future__ import annotations

DEMO = None
'''

FILES["PACKAGE/nodes/__init__.py"] = '''\
"""The plant's ROS 2 nodes, one module per role (``sim``, ``estimator``, ``controller``), each
with ``PARAMETERS`` (its ROS parameter specs, declared in ``parameters.py``) and ``make_node()``;
run by the node executables
(``cable_sim_node --plant NAME``, ``payload_estimator --plant NAME``, ``pd_feedforward --plant
NAME``). Nodes are adapters: messages to arrays, one call into the plant's ROS-free modules,
arrays to messages."""
'''

FILES["PACKAGE/nodes/parameters.py"] = '''\
"""The ROS parameters of the plant's nodes, declared once (as generate_parameter_library keeps a
node's parameters in a YAML file beside it): :data:`SIM` (``cable_sim_node``), :data:`ESTIMATOR`
(``payload_estimator``), :data:`CONTROLLER` (``pd_feedforward``). Each is a tuple of typed specs
(:class:`cablelab.ros.params.Param`: name, default, description, unit, range or choices) the node
declares with descriptors and validates; ``NODE --plant NAME --help`` lists them."""
from __future__ import annotations

from cablelab.ros.params import START_GATE, Param

#: ``cable_sim_node --plant NAME``
SIM = (
    Param("description", "", "plant description: YAML file or text (empty = the package's data/NAME.yaml)"),
    Param("damping", 0.05, "hinge damping (the effect the nominal model lacks)", "N m s/rad", ge=0.0, le=100.0),
    Param("drive", "builtin", "the torque: the built-in chirp or /NAME/effort_commands",
          choices=("builtin", "topic")),
    Param("rate", 200.0, "publishing rate", "Hz", ge=1.0, le=1000.0),
    Param("duration", 8.0, "simulated time after which the node exits", "s", gt=0.0, le=3600.0),
    Param("realtime_factor", 4.0, "simulated seconds per wall second", gt=0.0, le=1000.0),
    Param("torque_noise", 0.01, "standard deviation of the measured torque", "N m", ge=0.0, le=100.0),
    Param("seed", 0, "seed of the noise generator", ge=0),
    Param("command_timeout", 0.5, "a command older than this means zero torque", "s wall", gt=0.0),
) + START_GATE

#: ``payload_estimator --plant NAME``
ESTIMATOR = (
    Param("forgetting", 1.0, "forgetting factor of the recursive least squares (1 = none)", gt=0.0, le=1.0),
    Param("publish_every", 20, "publish the estimate every this many samples", ge=1, le=10 ** 9),
)

#: ``pd_feedforward --plant NAME``
CONTROLLER = (
    Param("duration", 8.0, "length of the chirp", "s", gt=0.0, le=3600.0),
    Param("amplitude", 0.3, "amplitude of the chirp", "N m", ge=0.0, le=1e3),
)
'''

FILES["PACKAGE/nodes/sim.py"] = '''\
"""``cable_sim_node --plant NAME``: the simulator (:class:`~..sim.CLASSSim`) at ``rate`` Hz of
simulated time, as fast as ``realtime_factor`` allows, until ``duration`` s. The torque is the
built-in chirp (:func:`~..control.chirp`, ``drive:=builtin``) or the latest
``/NAME/effort_commands`` (``drive:=topic``; a stale command means zero torque). Publishes
``/NAME/joint_states`` (angle, rate, applied torque plus ``torque_noise``), ``/clock`` and
``/plant_description``. ROS parameters: :data:`.parameters.SIM`.
"""
from __future__ import annotations

import time
from pathlib import Path

import numpy as np
from sensor_msgs.msg import JointState
from std_msgs.msg import Float64MultiArray

from cablelab.description import load_description
from cablelab.ros import convert
from cablelab.ros.clock import ClockPublisher
from cablelab.ros.plant_node import PlantNode
from cablelab.ros.qos import publisher_qos, stream_qos

from .. import topics
from ..control import chirp
from ..mjcf import JOINT
from ..sim import CLASSSim
from .parameters import SIM as PARAMETERS

DEFAULT_DESCRIPTION = Path(__file__).resolve().parent.parent / "data" / "NAME.yaml"


class CLASSSimNode(PlantNode):
    def __init__(self):
        super().__init__("cable_sim_node")
        v = self.declare_params(PARAMETERS)
        desc = load_description(v.description or DEFAULT_DESCRIPTION)
        self.sim = CLASSSim(desc.NAME, v.damping)
        self.rate, self.duration, self.noise = v.rate, v.duration, v.torque_noise
        self.builtin = v.drive == "builtin"
        self.rng = np.random.default_rng(v.seed)
        self.command = 0.0
        self.done = False
        self.inputs.add("effort_commands", timeout=v.command_timeout, length=1, required=not self.builtin)
        self.start_gate()
        self.publish_description(desc)
        self.pub = self.create_publisher(JointState, topics.JOINT_STATES, publisher_qos())
        self.create_subscription(Float64MultiArray, topics.EFFORT_COMMANDS, self.on_command, stream_qos())
        self.clock = ClockPublisher(self)
        self.last_publish = time.monotonic()
        self.start_diagnostics()
        self.create_timer(1.0 / (self.rate * v.realtime_factor), self.tick)

    def on_command(self, msg: Float64MultiArray) -> None:
        values = convert.float_array(msg)
        if self.inputs.accept("effort_commands", values, time.monotonic()):
            self.command = float(values[0])

    def publish(self, tau: float) -> None:
        t, q, qd = self.sim.state()
        self.clock.publish(t)
        measured = tau + self.noise * self.rng.standard_normal()
        self.pub.publish(convert.joint_state_msg(t, [JOINT], [q], [qd], [measured]))
        self.last_publish = time.monotonic()

    def tick(self) -> None:
        if self.done or self.waiting_for_subscribers(self.pub, self.last_publish, lambda: self.publish(0.0)):
            return
        if self.builtin:
            tau = float(chirp(self.sim.t, self.duration))
        else:
            tau = self.command if self.inputs.fresh("effort_commands", time.monotonic()) else 0.0
        self.sim.advance(tau, 1.0 / self.rate)
        self.publish(tau)
        self.done = self.sim.t >= self.duration

    def extend_status(self, level, msg, values):
        values["sim time s"] = f"{self.sim.t:.3f}"
        return level, msg, values


def make_node() -> PlantNode:
    return CLASSSimNode()
'''

FILES["PACKAGE/nodes/estimator.py"] = '''\
"""``payload_estimator --plant NAME``: recursive least squares of the nominal model
``tau = I qdd`` from ``/NAME/joint_states`` (qdd from consecutive velocities, the torque held over
the period), published as ``/NAME/parameter_estimate`` ``[I]`` every ``publish_every`` samples.
ROS parameters: :data:`.parameters.ESTIMATOR`.
"""
from __future__ import annotations

import time

from sensor_msgs.msg import JointState
from std_msgs.msg import Float64MultiArray

from cablelab.rls import RecursiveLeastSquares
from cablelab.ros import convert
from cablelab.ros.plant_node import PlantNode
from cablelab.ros.qos import catch_up_qos, publisher_qos

from .. import topics
from .parameters import ESTIMATOR as PARAMETERS


class CLASSEstimator(PlantNode):
    def __init__(self):
        super().__init__("payload_estimator")
        v = self.declare_params(PARAMETERS)
        self.rls = RecursiveLeastSquares(1, lam=v.forgetting, p0=1e4)
        self.every = v.publish_every
        self.prev = None     # (t, qd)
        self.inputs.add("joint_states", timeout=0.5, length=1)
        self.pub = self.create_publisher(Float64MultiArray, topics.PARAMETER_ESTIMATE, publisher_qos())
        self.create_subscription(JointState, topics.JOINT_STATES, self.on_state, catch_up_qos())
        self.start_diagnostics()

    def on_state(self, msg: JointState) -> None:
        t, _names, q, qd, eff = convert.joint_state_arrays(msg)
        if not self.inputs.accept("joint_states", qd, time.monotonic()) or eff is None or eff.size != 1:
            return
        prev, self.prev = self.prev, (t, float(qd[0]))
        if prev is None or not t > prev[0]:
            return
        # the torque reported with a sample is the one held over the period ending there
        self.rls.update([[(qd[0] - prev[1]) / (t - prev[0])]], [eff[0]])
        if self.rls.n % self.every == 0:
            self.pub.publish(convert.float_array_msg(self.rls.theta))

    def extend_status(self, level, msg, values):
        values["I"] = f"{self.rls.theta[0]:.6g}"
        return level, msg, values


def make_node() -> PlantNode:
    return CLASSEstimator()
'''

FILES["PACKAGE/nodes/controller.py"] = '''\
"""``pd_feedforward --plant NAME``: on every ``/NAME/joint_states`` publishes the chirp torque
(:func:`~..control.chirp`) at the state's stamp on ``/NAME/effort_commands`` (run the simulator
with ``drive:=topic``). ROS parameters: :data:`.parameters.CONTROLLER`.
"""
from __future__ import annotations

import time

from sensor_msgs.msg import JointState
from std_msgs.msg import Float64MultiArray

from cablelab.ros import convert
from cablelab.ros.plant_node import PlantNode
from cablelab.ros.qos import publisher_qos, stream_qos

from .. import topics
from ..control import chirp
from .parameters import CONTROLLER as PARAMETERS


class CLASSController(PlantNode):
    def __init__(self):
        super().__init__("pd_feedforward")
        v = self.declare_params(PARAMETERS)
        self.duration, self.amplitude = v.duration, v.amplitude
        self.inputs.add("joint_states", timeout=0.5, length=1)
        self.pub = self.create_publisher(Float64MultiArray, topics.EFFORT_COMMANDS, publisher_qos())
        self.create_subscription(JointState, topics.JOINT_STATES, self.on_state, stream_qos())
        self.start_diagnostics()

    def on_state(self, msg: JointState) -> None:
        t, _names, q, _qd, _eff = convert.joint_state_arrays(msg)
        if self.inputs.accept("joint_states", q, time.monotonic()):
            tau = float(chirp(t, self.duration, self.amplitude))
            self.pub.publish(convert.command_msg([tau], stamp=t))


def make_node() -> PlantNode:
    return CLASSController()
'''

FILES["PACKAGE/data/NAME.yaml"] = '''\
plant: NAME
name: NAME (default description of the nodes)
NAME:
  inertia: 0.08
'''

FILES["PACKAGE/README.md"] = '''\
# The `NAME` plant

A hinge of inertia `I` driven at its joint (replace with what the machine is, its paper and what
the nominal model leaves out). Written from the cablelab plant template (`cablelab new-plant
NAME`); docs/architecture.md of cablelab, "The plant template", lists what each file provides.

| file | provides |
|---|---|
| `__init__.py` | the one registration place (`register_plant(PLANT)`, imports the effects) |
| `plant.py` | `PLANT`: dataset, nominal model, candidates, description section, topics |
| `description.py` | the `NAME:` description section (parse, dump) |
| `dataset.py` | bag -> `Dataset` |
| `effects.py` | the plant's effects (regressors), registered by id |
| `control.py` | control laws (ROS-free) |
| `closed_form.py` | closed forms of the law: the oracle of the tests |
| `mjcf.py` | `build_mjcf(...)`: the MuJoCo model |
| `sim.py` | the ROS-free simulator, offline runs and bags |
| `topics.py` | the topic names, defined once |
| `demo.py` | the part of `./run demo` (none yet) |
| `nodes/{sim,estimator,controller}.py` | the ROS 2 node adapters |
| `nodes/parameters.py` | the nodes' ROS parameters (`SIM`, `ESTIMATOR`, `CONTROLLER`), declared once |
| `data/NAME.yaml` | the default description |

Install with `pip install -e .` next to `pyproject.toml`; then `cablelab diagnose BAG`,
`cable_sim_node --plant NAME` etc. know the plant. Run its tests with `python -m pytest`.
'''

FILES["PACKAGE/closed_form.py"] = '''\
"""Closed forms of the plant's law: the oracle the package's tests check the simulator against
(replace them with the machine's own: an equilibrium, a period, a conserved quantity)."""
from __future__ import annotations

import numpy as np

#: the constant-torque run of the test: torque (N m), duration (s), sample rate (Hz)
TORQUE, DURATION, RATE = 0.2, 2.0, 100.0


def constant_torque(section, run: dict) -> dict[str, tuple]:
    """The undamped hinge from rest under :data:`TORQUE`: ``q = tau t^2 / (2 I)``,
    ``qd = tau t / I``.

    Args:
        section: the description section; run: the simulator's run (``t``, ``q``, ``qd``).
    Returns:
        name -> (simulated, closed form, rtol, atol).
    """
    t, inertia = run["t"], section.inertia
    return {"q": (run["q"], TORQUE * t ** 2 / (2 * inertia), 1e-2, 1e-4),
            "qd": (run["qd"], TORQUE * t / inertia, 1e-2, 1e-4)}
'''

FILES["test_PACKAGE.py"] = '''\
"""Tests of the NAME plant (written by ``cablelab new-plant``; extend them with the plant's law).

Oracles: the closed form of the plant's law (:mod:`PACKAGE.closed_form`, which a new plant
replaces); the damping MuJoCo integrates against the viscous friction ``cablelab diagnose``
identifies from a recorded run; the entry-point discovery in a fresh interpreter."""
from __future__ import annotations

import json
import os
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest

HERE = Path(__file__).resolve().parent
DAMPING = 0.05   # N m s/rad, the truth the nominal model lacks


def plant_env(tmp_path: Path) -> dict:
    """Environment in which the package is installed: PYTHONPATH with it and a dist-info that
    announces its entry point (what ``pip install -e .`` would write)."""
    site = tmp_path / "site"
    dist = site / "NAME_plant-0.1.0.dist-info"
    dist.mkdir(parents=True)
    (dist / "METADATA").write_text("Metadata-Version: 2.1\\nName: NAME-plant\\nVersion: 0.1.0\\n")
    (dist / "entry_points.txt").write_text("[cablelab.plants]\\nNAME = PACKAGE\\n")
    path = os.pathsep.join([str(HERE), str(site), os.environ.get("PYTHONPATH", "")])
    return {**os.environ, "PYTHONPATH": path.rstrip(os.pathsep)}


def section():
    from cablelab.description import load_description

    return load_description(HERE / "PACKAGE" / "data" / "NAME.yaml").NAME


def test_registered_through_the_entry_point(tmp_path):
    code = ("from cablelab.registry import available_plants, get_plant; "
            "p = get_plant('NAME'); print(p.name in available_plants(), p.package)")
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True,
                         env=plant_env(tmp_path), check=True).stdout.split()
    assert out == ["True", "PACKAGE"]


def test_description_section_round_trip_and_one_line_errors():
    """The dumped section parses back equal; each field made negative is refused in one line
    naming it."""
    from cablelab.errors import CablelabError
    from PACKAGE.description import dump_section, parse_section

    sec = section()
    good = dump_section(sec)
    assert parse_section(good) == sec
    for key in good:
        with pytest.raises(CablelabError) as err:
            parse_section({**good, key: -1.0})
        assert key in str(err.value) and "\\n" not in str(err.value)


def test_simulator_follows_the_closed_form():
    """A constant torque from rest, simulated, against the law's closed form
    (:func:`PACKAGE.closed_form.constant_torque`)."""
    from PACKAGE import closed_form
    from PACKAGE.sim import simulate

    sec = section()
    run = simulate(sec, closed_form.DURATION, closed_form.RATE, lambda t: closed_form.TORQUE)
    for name, (got, want, rtol, atol) in closed_form.constant_torque(sec, run).items():
        assert np.allclose(got, want, rtol=rtol, atol=atol), (name, got, want)


def test_diagnose_finds_the_hidden_damping(tmp_path):
    """A run with hinge damping, recorded as a bag: ``cablelab diagnose`` ranks viscous joint
    friction first, with the damping MuJoCo integrated."""
    from PACKAGE.control import chirp
    from PACKAGE.sim import simulate, write_bag

    text = (HERE / "PACKAGE" / "data" / "NAME.yaml").read_text()
    run = simulate(section(), 8.0, 200.0, lambda t: chirp(t, 8.0), damping=DAMPING)
    bag = tmp_path / "run"
    write_bag(bag, run, text, torque_noise=0.01)
    res = subprocess.run([sys.executable, "-m", "cablelab.cli", "diagnose", str(bag), "--json"],
                         capture_output=True, text=True, env=plant_env(tmp_path), timeout=300)
    assert res.returncode == 0, res.stderr
    out = json.loads(res.stdout)
    top = out["ranking"][0]
    assert out["plant"] == "NAME" and top["effect"] == "joint_viscous_friction", out["ranking"]
    assert top["params"]["Fv"] == pytest.approx(DAMPING, rel=0.15)
'''


def check_name(name: str) -> str:
    """``name`` if it is a valid plant id (lowercase identifier, not a Python keyword), else a
    one-line error."""
    if not re.fullmatch(r"[a-z][a-z0-9_]*", name or "") or keyword.iskeyword(name):
        raise CablelabError(f"plant name {name!r}: expected a lowercase identifier "
                            "(letters, digits, _; starting with a letter)")
    return name


def plant_files(name: str) -> dict[str, str]:
    """Relative path -> text of every file of the plant ``name``'s package directory."""
    check_name(name)
    cls = "".join(p.capitalize() for p in name.split("_"))
    package = f"{name}_plant"

    def fill(text: str) -> str:
        return text.replace("PACKAGE", package).replace("CLASS", cls).replace("NAME", name)

    return {fill(path): fill(text) for path, text in FILES.items()}


def write_plant(name: str, out: Path) -> list[Path]:
    """Write the package directory of plant ``name`` to ``out`` (which must not exist yet).
    Returns the files written.

    Raises:
        CablelabError: a bad name, or ``out`` exists (nothing is overwritten).
    """
    files = plant_files(name)
    out = Path(out)
    if out.exists():
        raise CablelabError(f"{out}: already exists (new-plant never overwrites; choose another -o)")
    written = []
    for rel, text in files.items():
        path = out / rel
        path.parent.mkdir(parents=True, exist_ok=True)
        path.write_text(text)
        written.append(path)
    return written
