"""Regenerate the mjcf plant's shipped bags (``./run python src/cablelab/cablelab/plants/mjcf/data/make_bags.py [NAME ...]``).

Each bag is a closed-loop run of one shipped example recorded over DDS from the plant's own
nodes: ``cable_sim_node --plant mjcf`` (the truth), ``pd_feedforward --plant mjcf`` (PD + the
described model's inverse dynamics, tracking its built-in sine), ``payload_estimator --plant
mjcf`` when the description names a ``payload_body``, and ``cablelab record --plant mjcf``. The
truth carries an effect the description lacks (``CASES``, the README's table):

* ``arm3_payload``: the three-joint arm carries 1.5 kg on ``tool`` (the simulator's
  ``payload_mass``);
* ``gantry_friction``: the gantry crane's bridge and trolley run with viscous friction
  (MuJoCo joint ``damping`` 200 and 100 N s/m in the simulated model; 8 s at 250 Hz);
* ``cablecam_payload``: the four-cable camera robot's carriage carries a 2 kg camera.

For a hidden effect the simulator has no parameter for (the friction), the simulator runs the
truth model and the bag's ``/plant_description`` is then replaced by the described model (the
example as shipped): every other message is copied byte for byte. The recording is trimmed to
the topics the workbench reads (joint states, whose efforts are the controller's commands as
applied, tensions, the live payload estimate, the description; 12 s at 100 Hz) so that each bag
stays a few hundred kB.
"""
from __future__ import annotations

import shutil
import sys
import tempfile
import time
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

HERE = Path(__file__).resolve().parent
#: topics kept in a shipped bag (the ground truth equals the joint states: no sensor noise; the
#: commands are the joint states' efforts, as applied)
KEPT = ("/plant_description", "/mjcf/joint_states", "/mjcf/cable_tensions", "/mjcf/payload_estimate")


@dataclass(frozen=True)
class Case:
    """One shipped bag.

    Args:
        example: the example's file name (``plants/mjcf/examples``); section: the rest of the
            ``mjcf:`` section; sim: the simulator's parameters (besides the description);
        controller: ``pd_feedforward``'s parameters; truth: ``{joint: {attribute: value}}`` set in
            the simulated model only. The hidden effect each makes, as ``cablelab identify`` names
            it, is :data:`cablelab.plants.mjcf.demo.SHIPPED` (the README's table).
    """

    example: str
    section: dict
    sim: dict = field(default_factory=dict)
    controller: dict = field(default_factory=dict)
    truth: dict = field(default_factory=dict)
    duration: float = 12.0


CASES = {
    "arm3_payload": Case(
        "arm3.xml", {"payload_body": "tool"},
        sim={"payload_mass": 1.5, "rate": 100.0},
        controller={"reference_source": "sine", "amplitude": 0.4, "frequency": 0.4}),
    "gantry_friction": Case(
        "gantry.xml", {},
        # 250 Hz: an effort is the force applied over the period before its stamp, half a
        # period late; at 100 Hz that 5 ms lag would rank before the friction
        sim={"rate": 250.0},
        controller={"reference_source": "sine", "amplitude": 0.4, "frequency": 0.3},
        truth={"bridge": {"damping": 200.0}, "trolley": {"damping": 100.0}}, duration=8.0),
    "cablecam_payload": Case(
        "cablecam.xml", {"payload_body": "carriage",
                         "tendons": ["cable_1", "cable_2", "cable_3", "cable_4"]},
        sim={"payload_mass": 2.0, "rate": 100.0},
        controller={"reference_source": "sine", "amplitude": 0.4, "frequency": 0.3}),
}


def log(msg: str) -> None:
    print(f"[make_bags] {msg}", file=sys.stderr, flush=True)


def truth_xml(xml: str, truth: dict) -> str:
    """The example with the truth's joint attributes set (MuJoCo's model editor, MjSpec)."""
    import mujoco

    spec = mujoco.MjSpec.from_string(xml)
    for joint, attrs in truth.items():
        for attr, value in attrs.items():
            old = getattr(spec.joint(joint), attr)
            if hasattr(old, "__len__"):      # newer MuJoCo: a coefficient vector, linear first
                old = list(old)
                old[0] = value
                value = old
            setattr(spec.joint(joint), attr, value)
    spec.compile()
    return spec.to_xml()


def descriptions(case: Case) -> tuple[str, str]:
    """``(described, simulated)`` description YAML texts of a case (model inline)."""
    from cablelab.plants.mjcf.examples import HERE as EXAMPLES, text
    from cablelab.plants.mjcf.sim import description_yaml

    xml = text(EXAMPLES / case.example)
    described = description_yaml(xml, **case.section)
    simulated = description_yaml(truth_xml(xml, case.truth), **case.section) if case.truth else described
    return described, simulated


def record_case(name: str, case: Case, work: Path) -> Path:
    """The closed-loop run of ``case`` over DDS into ``work/name_raw``; returns the bag."""
    from cablelab.ros.launch import Launcher, unique_domain_id
    from cablelab.ros.sim_progress import SimProgress

    work.mkdir(parents=True, exist_ok=True)
    _described, simulated = descriptions(case)
    desc_file = work / f"{name}.yaml"
    desc_file.write_text(simulated)
    raw = work / f"{name}_raw"
    # the live payload estimate where the joint efforts carry the load (the estimator node does
    # not take cable tensions)
    estimator = bool(case.section.get("payload_body")) and not case.section.get("tendons")
    with Launcher(domain_id=unique_domain_id(7), log_dir=work / f"{name}_logs") as launch:
        launch.start("recorder", [sys.executable, "-m", "cablelab.cli", "record", "--plant", "mjcf",
                                  "-o", raw, "--overwrite", "--quiet"])
        launch.wait_for_subscribers(["/mjcf/joint_states", "/mjcf/effort_commands"], timeout=300,
                                    node_name="cablelab_recorder")
        if estimator:
            launch.node("estimator", "payload_estimator", "mjcf", {"window": 4.0, "publish_every": 200})
        launch.node("controller", "pd_feedforward", "mjcf", case.controller)
        launch.node("sim", "cable_sim_node", "mjcf", {"description": str(desc_file), "markers_rate": 0.0,
                                                      "wait_for_subscribers": 3 if estimator else 2,
                                                      **case.sim})
        with SimProgress(launch.probe(), case.duration, name) as bar:
            bar.wait_for(launch, case.duration, name, work)
        time.sleep(0.5)
        launch.stop_all_checked(name, work)
    return raw


def ship(raw: Path, dst: Path, described: str) -> Path:
    """Copy the kept topics of ``raw`` byte for byte into ``dst``, with ``described`` as its
    ``/plant_description``."""
    from cablelab.bags import BagWriter, open_bag

    bag = open_bag(raw)
    js_t = bag.raw("/mjcf/joint_states")[0]
    stamps = bag.joint_state("/mjcf/joint_states").t
    if np.any(np.diff(stamps) < 0):
        raise RuntimeError(f"{raw}: /mjcf/joint_states stamps go back in time (another simulator "
                           "on this ROS domain?)")
    if dst.exists():
        shutil.rmtree(dst)
    with BagWriter(dst) as w:
        w.write_description(described, t=int(js_t[0]) * 1e-9)
        for topic, msgtype in bag.topics.items():
            if topic not in KEPT or topic == "/plant_description":
                continue
            w.add_topic(topic, msgtype)
            t_ns, raws = bag.raw(topic)
            for t, r in zip(t_ns.tolist(), raws):
                w.write_raw(topic, t, r)
    (dst / ".cablelab-output").unlink(missing_ok=True)
    return dst


def main(argv: list[str] | None = None) -> int:
    names = list(argv if argv is not None else sys.argv[1:]) or list(CASES)
    unknown = [n for n in names if n not in CASES]
    if unknown:
        print(f"make_bags: unknown bag {unknown[0]} (known: {', '.join(CASES)})", file=sys.stderr)
        return 2
    from cablelab.errors import CablelabError

    with tempfile.TemporaryDirectory(prefix="mjcf-bags-") as tmp:
        for name in names:
            case = CASES[name]
            t0 = time.monotonic()
            for attempt in range(3):
                try:
                    ship(record_case(name, case, Path(tmp) / f"{attempt}"), HERE / name,
                         descriptions(case)[0])
                    break
                except (RuntimeError, CablelabError) as exc:   # a dead node, a stalled machine
                    log(f"{name}: {exc}; again")
            else:
                raise RuntimeError(f"{name}: three recordings failed")
            size = sum(f.stat().st_size for f in (HERE / name).iterdir())
            log(f"wrote {HERE / name} ({size / 1e3:.0f} kB, {time.monotonic() - t0:.0f} s)")
    return 0


if __name__ == "__main__":
    sys.exit(main())
