"""Model overlay bags (``compare --out``, ``diagnose --greedy --out``): the measurement, the
model's prediction and the residual as JointState topics beside the copied input topics.

Oracle: the metrics of ``compare --json`` recomputed from the bag's values with numpy (NRMSE =
rms(e) / rms(y), MAE, max |e|, Pearson), the bag read by two independent readers (rosbags'
AnyReader and the mcap package), and the input's messages byte for byte."""
import json
from pathlib import Path

import numpy as np
import pytest

from cablelab.bags import BagWriter
from cablelab.cli import main
from cablelab.description import load_description
from cablelab.plants.axis.sim import AxisTruth
from cablelab.plants.axis.truth import simulate_axis

ROOT = Path(__file__).resolve().parents[2]
EMPS = ROOT / "bags" / "emps"


def _read_rosbags(path) -> dict:
    """topic -> list of (stamp s, names, effort array, raw bytes) with rosbags' own reader."""
    from rosbags.highlevel import AnyReader
    from rosbags.typesys import Stores, get_typestore

    out: dict = {}
    with AnyReader([Path(path)], default_typestore=get_typestore(Stores.ROS2_JAZZY)) as r:
        for conn, t_ns, raw in r.messages():
            msg = r.deserialize(raw, conn.msgtype)
            stamp = msg.header.stamp.sec + 1e-9 * msg.header.stamp.nanosec if hasattr(msg, "header") else t_ns * 1e-9
            out.setdefault(conn.topic, []).append((stamp, t_ns, msg, bytes(raw)))
    return out


def _channel(rows, names):
    return np.array([[r[2].effort[list(r[2].name).index(n)] for n in names] for r in rows])


@pytest.fixture(scope="module")
def emps_overlay(tmp_path_factory):
    out = tmp_path_factory.mktemp("ov") / "emps_overlay"
    import contextlib
    import io

    buf = io.StringIO()
    with contextlib.redirect_stdout(buf):
        assert main(["compare", str(EMPS), "--out", str(out), "--json"]) == 0
    return out, json.loads(buf.getvalue())


def test_emps_overlay_values_equal_compare_metrics(emps_overlay):
    out, doc = emps_overlay
    topics = _read_rosbags(out)
    names = list(doc["channels"])
    meas = _channel(topics["/axis/model/measured"], names)
    pred = _channel(topics["/axis/model/prediction"], names)
    res = _channel(topics["/axis/model/residual"], names)
    ok = np.isfinite(meas).all(axis=1)
    assert ok.sum() == doc["samples"]
    np.testing.assert_allclose(res[ok], meas[ok] - pred[ok], rtol=0, atol=1e-9)
    for c, ch in enumerate(names):
        y, e = meas[ok, c], res[ok, c]
        m = doc["channels"][ch]
        assert np.sqrt(np.mean(e ** 2)) / np.sqrt(np.mean(y ** 2)) == pytest.approx(m["nrmse"], rel=1e-9)
        assert np.mean(np.abs(e)) == pytest.approx(m["mae"], rel=1e-9)
        assert np.max(np.abs(e)) == pytest.approx(m["max_abs"], rel=1e-9)
        assert np.corrcoef(y, pred[ok, c])[0, 1] == pytest.approx(m["pearson"], rel=1e-9)
    # the EMPS model misses Coulomb friction: the residual is far from zero (not a copy of y)
    assert 0.05 < doc["channels"]["joint"]["nrmse"] < 0.5


def test_emps_overlay_is_stamped_like_its_input_and_copies_it(emps_overlay):
    out, _ = emps_overlay
    topics = _read_rosbags(out)
    inp = _read_rosbags(EMPS)
    for topic, rows in inp.items():   # every input message, same log time, same bytes
        assert [(r[1], r[3]) for r in topics[topic]] == [(r[1], r[3]) for r in rows], topic
    stamps_in = np.array([r[0] for r in inp["/axis/joint_states"]])
    for kind in ("measured", "prediction", "residual"):
        rows = topics[f"/axis/model/{kind}"]
        st = np.array([r[0] for r in rows])
        assert np.array_equal(st, np.array([r[1] for r in rows]) * 1e-9) or \
            np.allclose(st, np.array([r[1] for r in rows]) * 1e-9, atol=1e-9)   # header = log time
        idx = np.clip(np.searchsorted(stamps_in, st), 0, len(stamps_in) - 1)
        near = np.minimum(np.abs(stamps_in[idx] - st), np.abs(stamps_in[np.maximum(idx - 1, 0)] - st))
        assert near.max() < 1e-6, kind      # each sample at an input stamp
    stages = json.loads(topics["/axis/model/stages"][0][2].data)
    assert stages["channels"] == ["joint"] and stages["stages"][0]["effects"]


def test_emps_overlay_opens_with_the_mcap_reader(emps_overlay):
    from mcap.reader import make_reader

    out, _ = emps_overlay
    (mcap_file,) = out.glob("*.mcap")
    counts: dict = {}
    with open(mcap_file, "rb") as f:
        reader = make_reader(f)
        for schema, channel, message in reader.iter_messages():
            counts[channel.topic] = counts.get(channel.topic, 0) + 1
            assert schema.encoding == "ros2msg" and channel.message_encoding == "cdr"
        summary = reader.get_summary()
    assert counts["/axis/model/prediction"] == counts["/axis/model/residual"] > 20000
    assert sum(counts.values()) == summary.statistics.message_count


def test_overlay_never_into_the_input_nor_over_an_output(emps_overlay, tmp_path, capsys):
    out, _ = emps_overlay
    before = sorted((p.name, p.stat().st_size) for p in EMPS.iterdir())
    assert main(["compare", str(EMPS), "--out", str(EMPS / "x")]) == 2
    assert "input" in capsys.readouterr().err
    assert main(["compare", str(EMPS), "--out", str(out)]) == 2
    assert "--overwrite" in capsys.readouterr().err
    assert sorted((p.name, p.stat().st_size) for p in EMPS.iterdir()) == before
    assert main(["diagnose", str(EMPS), "--out", str(tmp_path / "d")]) == 2
    assert "--greedy" in capsys.readouterr().err
    assert not (tmp_path / "d").exists()


def test_greedy_overlay_has_every_stage_and_the_final_model(tmp_path, capsys):
    desc = "plant: axis\nname: slide\naxis:\n  joint_type: prismatic\n  inertia: 2.0\n"
    run = simulate_axis(load_description(desc), AxisTruth(inertia=2.0, viscous=5.0, coulomb=3.0),
                        duration=12.0, fs=250.0, amplitude=0.3, noise_effort=0.05, seed=1)
    bag = tmp_path / "axis"
    with BagWriter(bag) as w:
        w.write_description(desc)
        w.write_joint_states("/axis/joint_states", run.t, ["joint"], run.q[:, None], None, run.effort[:, None])
    out = tmp_path / "greedy_overlay"
    assert main(["diagnose", str(bag), "--greedy", "--out", str(out), "--json"]) == 0
    doc = json.loads(capsys.readouterr().out)
    topics = _read_rosbags(out)
    steps = doc["greedy"]
    assert steps[1]["added"] == "joint_coulomb_friction"
    stages = json.loads(topics["/axis/model/stages"][0][2].data)["stages"]
    assert [s["stage"] for s in stages[:len(steps)]] == \
        ["nominal"] + [f"plus_{s['added']}" for s in steps[1:]]
    rms = []
    for st in stages[:len(steps)]:
        res = _channel(topics[f"/axis/model/{st['stage']}/residual"], ["joint"])
        rms.append(np.sqrt(np.nanmean(res ** 2)))
        assert st["effects"] == steps[len(rms) - 1]["effects"]
    assert rms[-1] < 0.5 * rms[0]       # the Coulomb term explains most of the nominal residual
    last = _channel(topics[f"/axis/model/{stages[len(steps) - 1]['stage']}/prediction"], ["joint"])
    final = _channel(topics["/axis/model/prediction"], ["joint"])
    np.testing.assert_array_equal(final, last)


def test_report_links_its_overlay_bag(tmp_path, capsys):
    from cablelab.bags import open_bag

    desc = "plant: axis\nname: slide\naxis:\n  joint_type: prismatic\n  inertia: 2.0\n"
    run = simulate_axis(load_description(desc), AxisTruth(inertia=2.0, viscous=5.0, coulomb=3.0),
                        duration=8.0, fs=250.0, amplitude=0.3, noise_effort=0.05, seed=2)
    bag = tmp_path / "axis"
    with BagWriter(bag) as w:
        w.write_description(desc)
        w.write_joint_states("/axis/joint_states", run.t, ["joint"], run.q[:, None], None, run.effort[:, None])
    out = tmp_path / "rep"
    assert main(["report", str(bag), "-o", str(out), "--json"]) == 0
    doc = json.loads(capsys.readouterr().out)
    assert "href='overlay'" in (out / "index.html").read_text()
    ov = open_bag(out / "overlay")
    stages = json.loads(ov.strings("/axis/model/stages")[-1])["stages"]
    assert stages[-1]["effects"] == doc["final"]
    assert ov.counts["/axis/joint_states"] == open_bag(bag).counts["/axis/joint_states"]
