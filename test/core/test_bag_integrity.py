"""Bags are checked against their own metadata and structure: a split bag missing one of its
files is an error (``--recover``: a warning with the counts), a damaged chunk is skipped with a
count and every intact chunk salvaged (reading and ``repair``), two disagreeing
/plant_description messages are an error naming both stamps, a junk description message says
what is wrong with it."""
from __future__ import annotations

import os
import shutil
from pathlib import Path

import numpy as np
import pytest
import yaml
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from robust_helpers import EMPS

from cablelab.bags import BagWriter, open_bag
from cablelab.bags.salvage import _summary, salvage_mcap
from cablelab.errors import CablelabError

FUZZ = settings(max_examples=int(os.environ.get("CABLELAB_FUZZ_EXAMPLES", "12")) * 3, deadline=None,
                derandomize=not os.environ.get("CABLELAB_FUZZ_RANDOM"),
                suppress_health_check=[HealthCheck.function_scoped_fixture, HealthCheck.too_slow])
DESC = "plant: axis\nname: chunks\naxis:\n  joint_type: prismatic\n"
CHUNKS, PER_CHUNK = 12, 50
TOPIC = "/axis/joint_states"


def _chunked_bag(path, chunks=CHUNKS, per=PER_CHUNK, t0=0.0):
    """A bag of ``chunks`` MCAP chunks of ``per`` joint states each (a flush per chunk)."""
    with BagWriter(path) as w:
        w.write_description(DESC, t=t0)
        for c in range(chunks):
            t = t0 + 0.001 * (np.arange(per) + c * per) + 0.0005
            w.write_joint_states(TOPIC, t, ["slide"], position=np.sin(t)[:, None],
                                 effort=np.cos(t)[:, None])
            w.flush()
    return path


def _messages(bag):
    """{(topic, log time ns): payload bytes} of every message."""
    out = {}
    for topic in bag.topics:
        t, raws = bag.raw(topic)
        out.update({(topic, int(k)): r for k, r in zip(t.tolist(), raws)})
    return out


def _chunk_spans(mcap: Path):
    """[(start, end)] byte ranges of the chunk records (from the summary's chunk index)."""
    data = mcap.read_bytes()
    starts = _summary(data)[2]
    spans = []
    for s in starts:
        n = int.from_bytes(data[s + 1:s + 9], "little")
        spans.append((s, s + 9 + n))
    return spans


def _chunk_messages(mcap: Path, spans):
    """Per chunk the set of message keys it holds (decoded from the clean file)."""
    from cablelab.bags.salvage import _decode_chunk

    data = mcap.read_bytes()
    schemas, channels, _, _ = _summary(data)
    out = []
    for a, b in spans:
        msgs = _decode_chunk(data, a + 9, b, dict(schemas), dict(channels))
        out.append({(channels[cid][0], lt) for cid, lt, _ in msgs})
    return out


def _corrupt(mcap: Path, at: int, junk: bytes) -> None:
    data = bytearray(mcap.read_bytes())
    data[at:at + len(junk)] = junk
    mcap.write_bytes(bytes(data))


# ----------------------------------------------------------------------------- damaged chunk
@pytest.fixture
def damaged(tmp_path):
    """A 12-chunk bag with 400 random bytes in its 5th chunk; (bag, clean messages, lost keys)."""
    bag = _chunked_bag(tmp_path / "bag")
    mcap = next(bag.glob("*.mcap"))
    clean = _messages(open_bag(bag))
    spans = _chunk_spans(mcap)
    per_chunk = _chunk_messages(mcap, spans)
    a, _ = spans[4]
    _corrupt(mcap, a + 200, np.random.default_rng(7).integers(0, 256, 400, dtype=np.uint8).tobytes())
    return bag, clean, per_chunk[4], len(spans)


def test_damaged_chunk_is_named_not_a_python_error(damaged):
    bag, _, lost, n = damaged
    with pytest.raises(CablelabError) as e:
        open_bag(bag)
    msg = str(e.value)
    assert "\n" not in msg and "damaged" in msg and f"1 of {n} chunks" in msg and "--recover" in msg, msg
    assert f"({len(lost)} messages)" in msg
    assert "int too large" not in msg


def test_recover_skips_the_damaged_chunk_and_keeps_the_rest(damaged):
    bag, clean, lost, n = damaged
    got = open_bag(bag, recover=True)
    assert got.recovered
    assert got.warnings == [f"{bag}: skipped 1 damaged chunk of {n}, {len(lost)} messages lost"]
    msgs = _messages(got)
    want = {k: v for k, v in clean.items() if k not in lost}
    assert msgs == want                    # every message of every intact chunk, byte for byte
    assert len(msgs) == len(clean) - len(lost)


def test_repair_salvages_the_intact_chunks(cli, damaged, tmp_path):
    bag, clean, lost, n = damaged
    res = cli("repair", bag, "-o", tmp_path / "fixed")
    assert res.code == 0, res.err
    assert f"skipped 1 damaged chunk of {n}, {len(lost)} messages lost" in res.out
    assert "complete)" not in res.out and "intact part" in res.out
    fixed = open_bag(tmp_path / "fixed")
    assert fixed.warnings == [] and not fixed.recovered
    assert _messages(fixed) == {k: v for k, v in clean.items() if k not in lost}


def test_damaged_chunk_reaches_the_verbs_warnings(cli, damaged):
    bag, _, lost, n = damaged
    res = cli("info", bag, "--recover")
    assert res.code == 0 and f"skipped 1 damaged chunk of {n}" in res.out, res.out
    res = cli("info", bag)
    assert res.code == 2 and len(res.err_lines) == 1 and "--recover" in res.err


@FUZZ
@given(chunk=st.integers(0, CHUNKS - 1), where=st.floats(0.0, 1.0), size=st.integers(1, 400),
       seed=st.integers(0, 2**32 - 1))
def test_fuzz_salvage_keeps_every_intact_chunk(tmp_path_factory, chunk, where, size, seed):
    """Random bytes anywhere in one chunk record: every message of every other chunk is read
    back byte for byte, nothing is invented beyond the original count, and the count of lost
    messages is what is missing."""
    d = tmp_path_factory.mktemp("fz")
    bag = _chunked_bag(d / "bag")
    mcap = next(bag.glob("*.mcap"))
    clean = _messages(open_bag(bag))
    spans = _chunk_spans(mcap)
    per_chunk = _chunk_messages(mcap, spans)
    a, b = spans[chunk]
    at = a + int(where * max(b - a - size, 0))
    _corrupt(mcap, at, np.random.default_rng(seed).integers(0, 256, size, dtype=np.uint8).tobytes())
    s = salvage_mcap(mcap)
    got = {(t, int(k)): r for t in s.times for k, r in zip(s.times[t], s.raws[t])}
    intact = set().union(*(m for i, m in enumerate(per_chunk) if i != chunk))
    intact |= {k for k in clean if k[0] == "/plant_description"} - per_chunk[chunk]
    for k in intact:
        assert got.get(k) == clean[k], k
    assert len(got) <= len(clean)
    assert s.damaged <= 1 and s.chunks == CHUNKS
    if s.damaged:
        assert s.lost == len(clean) - len(got)
    recovered = open_bag(bag, recover=True)    # the reader agrees with the salvage
    assert set(_messages(recovered)) >= intact


def test_truncated_and_damaged(tmp_path):
    """A killed writer's file with a damaged chunk inside: both said, the rest read."""
    bag = _chunked_bag(tmp_path / "bag")
    mcap = next(bag.glob("*.mcap"))
    spans = _chunk_spans(mcap)
    data = mcap.read_bytes()
    mcap.write_bytes(data[:spans[8][1] + 20])        # cut in the middle of what follows chunk 9
    (bag / "metadata.yaml").unlink()
    _corrupt(mcap, spans[2][0] + 300, b"\xff" * 64)
    with pytest.raises(CablelabError, match="truncated"):
        open_bag(bag)
    got = open_bag(bag, recover=True)
    assert got.recovered and len(got.warnings) == 1 and "skipped 1 damaged chunk of" in got.warnings[0]
    assert got.counts[TOPIC] == 8 * PER_CHUNK


def test_clean_bags_have_no_warning():
    assert open_bag(EMPS).warnings == []
    assert salvage_mcap(next(EMPS.glob("*.mcap"))).damaged == 0


# ----------------------------------------------------------------------------- split bags
def _split_bag(tmp_path):
    """A rosbag2 bag of two .mcap files (metadata listing both), from two written bags."""
    a = _chunked_bag(tmp_path / "a", chunks=3)
    b = _chunked_bag(tmp_path / "b", chunks=2, t0=1.0)
    out = tmp_path / "split"
    out.mkdir()
    shutil.copy(next(a.glob("*.mcap")), out / "split_0.mcap")
    shutil.copy(next(b.glob("*.mcap")), out / "split_1.mcap")
    meta = yaml.safe_load((a / "metadata.yaml").read_text())
    mb = yaml.safe_load((b / "metadata.yaml").read_text())
    info = meta["rosbag2_bagfile_information"]
    ib = mb["rosbag2_bagfile_information"]
    info["relative_file_paths"] = ["split_0.mcap", "split_1.mcap"]
    info["files"][0]["path"] = "split_0.mcap"
    info["files"].append(dict(ib["files"][0], path="split_1.mcap"))
    info["message_count"] += ib["message_count"]
    for tm, tb in zip(info["topics_with_message_count"], ib["topics_with_message_count"]):
        tm["message_count"] += tb["message_count"]
    (out / "metadata.yaml").write_text(yaml.safe_dump(meta))
    return out, ib["files"][0]["message_count"]


def test_complete_split_bag_reads_both_files(tmp_path):
    bag, _ = _split_bag(tmp_path)
    got = open_bag(bag)
    assert got.counts[TOPIC] == 5 * PER_CHUNK and got.warnings == []


def test_split_bag_missing_a_file_is_an_error(tmp_path, cli):
    bag, n_second = _split_bag(tmp_path)
    (bag / "split_1.mcap").unlink()
    with pytest.raises(CablelabError) as e:
        open_bag(bag)
    msg = str(e.value)
    assert "missing 1 of its 2 files" in msg and "split_1.mcap" in msg and f"{n_second} messages" in msg
    assert "--recover" in msg
    got = open_bag(bag, recover=True)
    assert got.counts[TOPIC] == 3 * PER_CHUNK and got.recovered
    assert len(got.warnings) == 1 and f"{n_second} messages" in got.warnings[0]
    res = cli("repair", bag, "-o", tmp_path / "fixed")
    assert res.code == 0 and "missing 1 of its 2 files" in res.out and "intact part" in res.out, res.out
    assert "(input was complete)" not in res.out
    assert open_bag(tmp_path / "fixed").counts[TOPIC] == 3 * PER_CHUNK


def test_message_count_against_metadata(tmp_path):
    """A bag whose file holds fewer messages than its metadata.yaml lists is said so."""
    bag = _chunked_bag(tmp_path / "bag", chunks=2)
    meta = yaml.safe_load((bag / "metadata.yaml").read_text())
    meta["rosbag2_bagfile_information"]["message_count"] += 7
    (bag / "metadata.yaml").write_text(yaml.safe_dump(meta))
    got = open_bag(bag)
    n = 2 * PER_CHUNK + 1
    assert got.warnings == [f"{bag}: metadata.yaml lists {n + 7} messages, the bag holds {n}"]


# ----------------------------------------------------------------------------- descriptions
def _with_descriptions(path, texts, stamps):
    with BagWriter(path) as w:
        w.write_strings("/plant_description", stamps, texts, transient_local=True)
        t = np.arange(100) * 0.01
        w.write_joint_states(TOPIC, t, ["slide"], position=t[:, None], effort=t[:, None])
    return path


def test_disagreeing_descriptions_are_an_error(tmp_path):
    other = DESC.replace("prismatic", "revolute")
    bag = open_bag(_with_descriptions(tmp_path / "b", [DESC, other], [0.0, 2.5]))
    with pytest.raises(CablelabError) as e:
        bag.description
    msg = str(e.value)
    assert "two different descriptions" in msg and "0.000 s" in msg and "2.500 s" in msg
    assert "--description" in msg


def test_disagreeing_descriptions_in_the_cli(tmp_path, cli):
    other = DESC.replace("prismatic", "revolute")
    bag = _with_descriptions(tmp_path / "b", [DESC, other], [0.0, 2.5])
    res = cli("compare", bag)
    assert res.code == 2 and len(res.err_lines) == 1 and "two different descriptions" in res.err
    res = cli("info", bag)                  # info still describes the bag, with the finding
    assert res.code == 0 and "two different descriptions" in res.out


def test_republished_description_is_fine(tmp_path):
    """The same description again (another formatting of the same YAML) is no conflict."""
    again = "plant: axis\naxis: {joint_type: prismatic}\nname: chunks\n"
    bag = open_bag(_with_descriptions(tmp_path / "b", [DESC, again, DESC], [0.0, 1.0, 2.0]))
    assert bag.description.plant == "axis"


@pytest.mark.parametrize("junk,words", [
    ("just some words", "not a YAML mapping"),
    ("[1, 2, 3]", "not a YAML mapping"),
    ("plant: [unclosed", "not valid YAML"),
    ("", "not a YAML mapping"),
])
def test_junk_description_message_says_what_is_wrong(tmp_path, junk, words):
    bag = open_bag(_with_descriptions(tmp_path / "b", [junk], [0.0]))
    with pytest.raises(CablelabError) as e:
        bag.description
    msg = str(e.value)
    assert words in msg and "/plant_description" in msg and "not found" not in msg, msg


# ----------------------------------------------------------------------------- bounded input
@pytest.mark.parametrize("path,words", [("/dev/zero", "not a regular file"),
                                        ("DIR", "is a directory"), ("BIG", "MiB")])
def test_description_file_read_is_bounded(cli, tmp_path, path, words):
    if path == "DIR":
        path = tmp_path
    elif path == "BIG":
        path = tmp_path / "big.yaml"
        with open(path, "wb") as fh:
            fh.truncate(17 * 2**20)        # sparse: 17 MiB, more than the 16 MiB limit
    res = cli("compare", EMPS, "--description", path)
    assert res.code == 2 and len(res.err_lines) == 1 and words in res.err and str(path) in res.err, res.err


@FUZZ
@given(cut=st.floats(0.05, 0.999))
def test_fuzz_truncation_is_not_damage(tmp_path_factory, cut):
    """A file cut anywhere (writer killed) is truncated, never "damaged": every complete chunk
    before the cut is read, byte for byte."""
    d = tmp_path_factory.mktemp("cut")
    bag = _chunked_bag(d / "bag")
    mcap = next(bag.glob("*.mcap"))
    clean = _messages(open_bag(bag))
    spans = _chunk_spans(mcap)
    per_chunk = _chunk_messages(mcap, spans)
    data = mcap.read_bytes()
    n = int(cut * len(data))
    mcap.write_bytes(data[:n])
    s = salvage_mcap(mcap)
    assert s.damaged == 0              # (a cut inside the summary loses no message at all)
    got = {(t, int(k)): r for t in s.times for k, r in zip(s.times[t], s.raws[t])}
    whole = set().union(*(m for (a, b), m in zip(spans, per_chunk) if b <= n))
    assert whole <= set(got)
    assert all(clean[k] == v for k, v in got.items())


def test_split_bag_with_a_damaged_chunk(tmp_path):
    """Each file of a split bag is checked on its own: a damaged chunk in the second file is
    named, and --recover keeps the first file and the intact chunks of the second."""
    bag, _ = _split_bag(tmp_path)
    mcap = bag / "split_1.mcap"
    _, b = _chunk_spans(mcap)[-1]
    _corrupt(mcap, b - 1000, b"\xee" * 300)          # inside the messages of its last chunk
    with pytest.raises(CablelabError, match="damaged MCAP file: 1 of 2 chunks"):
        open_bag(bag)
    got = open_bag(bag, recover=True)
    assert got.counts[TOPIC] == 4 * PER_CHUNK and got.recovered
    assert len(got.warnings) == 1 and "skipped 1 damaged chunk of 2" in got.warnings[0]


@pytest.mark.parametrize("info", [5, "text", {"relative_file_paths": "x"}, {"files": 3},
                                  {"relative_file_paths": ["/etc/passwd", "../other.mcap"]}])
def test_odd_metadata_is_never_a_traceback(tmp_path, info):
    """Metadata of another shape than rosbag2's (or listing files outside the bag): the bag's
    own .mcap is read, or one line; never a traceback, never a file outside the bag."""
    bag = _chunked_bag(tmp_path / "bag", chunks=2)
    (bag / "metadata.yaml").write_text(yaml.safe_dump({"rosbag2_bagfile_information": info}))
    got = open_bag(bag)
    assert got.counts[TOPIC] == 2 * PER_CHUNK
