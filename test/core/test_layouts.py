"""Foxglove and PlotJuggler layouts (``cablelab layout``): every topic and field a layout names
exists, in the plant's overlay bag (values present, the element at the index the layout uses)
or, for the live topics a recording need not hold, among the plant's contract topics with that
field in the message definition. The shipped layouts (layouts/) are what the command writes."""
import json
from pathlib import Path

import numpy as np
import pytest

from cablelab import cdr
from cablelab.bags import open_bag
from cablelab.cli import main
from cablelab.layouts import foxglove_references, plant_layout, plotjuggler_references
from cablelab.registry import available_plants, get_plant
from cablelab.topics import plant_topics

ROOT = Path(__file__).resolve().parents[2]
RECORDINGS = {"axis": "emps", "cdpr": "cdpr_m1_reference", "crane": "crane_control"}
JS = "sensor_msgs/msg/JointState"


def _has_field(msgtype: str, path: str) -> bool:
    """The dotted field path exists in the message definition (base or sequence leaf)."""
    ts = cdr.typestore()
    for part in path.split("."):
        fields = dict(ts.fielddefs[msgtype][1])
        if part not in fields:
            return False
        kind, spec = fields[part]
        msgtype = spec if kind.name == "NAME" else None
    return True


def _foxglove_targets(doc):
    """(topic, field, index) of every Foxglove path; ('topic', '', None) for a 3D topic."""
    out = []
    for topic, field in foxglove_references(doc):
        idx = None
        if field.endswith("]"):
            field, _, i = field[:-1].partition("[")
            idx = int(i)
        out.append((topic, field, idx))
    return out


def _pj_targets(xml_text, names: dict):
    """(topic, field, name) of every PlotJuggler curve: ``/topic/<name>/<field>`` for a
    JointState topic of ``names`` (its element names), else ``/topic/a/b``."""
    out = []
    for curve in plotjuggler_references(xml_text):
        for topic in names:
            if curve.startswith(topic + "/") and curve.count("/") == topic.count("/") + 2:
                _, name, field = curve[len(topic):].split("/")
                out.append((topic, field, name))
                break
        else:
            parts = curve.split("/")
            for k in range(len(parts) - 1, 1, -1):   # the longest topic prefix of the plant
                topic = "/".join(parts[:k])
                if topic in plant_topics(curve.split("/")[1]):
                    out.append((topic, ".".join(parts[k:]), None))
                    break
            else:
                out.append((curve, "", None))
    return out


def _check_in_bag(bag, contract, topic, field, index=None, name=None):
    if topic.endswith("/markers"):
        return    # the 3D topic: written by the simulators and compare --out when the plant has markers
    if bag is not None and bag.has(topic):
        typ = bag.topics[topic]
        assert _has_field(typ, field), (topic, field)
        if typ == JS:
            s = bag.joint_state(topic)
            col = s.names.index(name) if name is not None else index
            assert index is None or s.names[index] == (name or s.names[index]), (topic, index, name)
            assert col < len(s.names), (topic, index)
            assert np.isfinite(getattr(s, field)[:, col]).any(), (topic, field, col)
        return
    assert topic in contract, f"{topic} neither in the overlay bag nor a contract topic"
    assert _has_field(contract[topic], field), (topic, field)


@pytest.fixture(scope="module")
def overlays(tmp_path_factory):
    d = tmp_path_factory.mktemp("layouts")
    out = {}
    for plant, rec in RECORDINGS.items():
        path = d / f"{plant}_overlay"
        assert main(["compare", str(ROOT / "bags" / rec), "--out", str(path), "--json"]) == 0
        out[plant] = open_bag(path)
    return out


@pytest.mark.parametrize("plant", sorted(RECORDINGS))
def test_layout_topics_exist_in_the_overlay_bag(plant, overlays, capsys):
    bag = overlays[plant]
    contract = dict(plant_topics(plant))
    fox = json.loads(plant_layout(plant, "foxglove", bag=bag))
    targets = _foxglove_targets(fox)
    model_topics = {t for t, _, _ in targets if "/model/" in t}
    assert model_topics == {f"/{plant}/model/measured", f"/{plant}/model/prediction", f"/{plant}/model/residual"}
    for topic, field, idx in targets:
        if field:
            _check_in_bag(bag, contract, topic, field, index=idx)
    names = {t: bag.joint_state(t).names for t, ty in bag.topics.items() if ty == JS}
    names.update({t: n for t, n in (get_plant(plant).topic_names(bag.description) or {}).items()
                  if t not in names})
    pj = plant_layout(plant, "plotjuggler", bag=bag)
    for topic, field, name in _pj_targets(pj, names):
        _check_in_bag(bag, contract, topic, field, name=name)
    # every output channel has its measured-vs-model plot, and the residual plot has them all
    channels = json.loads(bag.strings(f"/{plant}/model/stages")[-1])["channels"]
    titles = [c["title"] for c in fox["configById"].values() if "title" in c]
    assert all(f"{ch}: measured vs model" in titles for ch in channels)


def test_cdpr_layout_plots_tensions_and_payload_estimate_against_truth(overlays):
    bag = overlays["cdpr"]
    fox = json.loads(plant_layout("cdpr", "foxglove", bag=bag))
    paths = {p["value"] for c in fox["configById"].values() for p in c.get("paths", ())}
    assert {f"/cdpr/cable_tensions.effort[{i}]" for i in range(8)} <= paths
    assert {"/cdpr/payload_estimate.inertia.m", "/cdpr/ground_truth/payload.inertia.m"} <= paths
    assert "/cdpr/markers" in fox["configById"]["3D!cdpr"]["topics"]


@pytest.mark.parametrize("plant", sorted(available_plants()))
def test_default_layouts_name_only_contract_or_model_topics(plant):
    """Without a bag: model channels from the plant, other names from its contract."""
    contract = dict(plant_topics(plant))
    p = get_plant(plant)
    names = dict(p.topic_names(None)) if p.topic_names else {}
    fox = json.loads(plant_layout(plant, "foxglove"))
    for topic, field, idx in _foxglove_targets(fox):
        if "/model/" in topic:
            assert topic.rsplit("/", 1)[1] in ("measured", "prediction", "residual") and idx < len(p.channels)
        elif field:
            assert topic in contract and _has_field(contract[topic], field), (topic, field)
            if idx is not None:
                assert idx < len(names[topic])
    model = {f"/{plant}/model/{k}": list(p.channels) for k in ("measured", "prediction", "residual")}
    for topic, field, name in _pj_targets(plant_layout(plant, "plotjuggler"), {**names, **model}):
        assert topic in contract or topic in model, topic
        assert _has_field(contract.get(topic, JS), field), (topic, field)
        if name is not None:
            assert name in {**names, **model}[topic]


@pytest.mark.parametrize("plant", sorted(available_plants()))
@pytest.mark.parametrize("tool,ext", [("foxglove", "foxglove.json"), ("plotjuggler", "plotjuggler.xml")])
def test_shipped_layouts_are_what_the_command_writes(plant, tool, ext, tmp_path, capsys):
    out = tmp_path / f"{plant}.{ext}"
    assert main(["layout", "--plant", plant, "--tool", tool, "-o", str(out)]) == 0
    shipped = ROOT / "layouts" / f"{plant}.{ext}"
    assert shipped.read_text() == out.read_text(), f"regenerate {shipped}: cablelab layout --plant {plant} --tool {tool} -o {shipped} --overwrite"
    assert main(["layout", "--plant", plant, "--tool", tool, "-o", str(out)]) == 2   # no overwrite unasked
    assert "--overwrite" in capsys.readouterr().err


def test_demo_prints_commands_that_open_its_bags_with_the_shipped_layouts(tmp_path):
    from cablelab.demo import open_commands

    lines = open_commands("cdpr", [tmp_path / "run"])
    assert lines[0].startswith("overlay ./run cablelab compare ") and f"--out {tmp_path}/run_overlay" in lines[0]
    pj = lines[1].split(" -l ")[1]
    fox = lines[2].split("Import ")[1]
    assert Path(pj).read_text().startswith("<?xml") and json.loads(Path(fox).read_text())["configById"]
    assert lines[1].startswith(f"plotjuggler -d {tmp_path}/run_overlay/run_overlay.mcap")


def test_layout_of_another_plants_bag_is_a_one_line_error(tmp_path, capsys):
    out = tmp_path / "x.json"
    assert main(["layout", "--plant", "crane", "--bag", str(ROOT / "bags" / "emps"), "-o", str(out)]) == 2
    err = capsys.readouterr().err.strip()
    assert err.count("\n") == 0 and "axis bag, not crane" in err and not out.exists()
