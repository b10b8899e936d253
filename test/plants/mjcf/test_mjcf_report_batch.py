"""The mjcf plant's shipped bags (``plants/mjcf/data/``, recorded over DDS from the plant's nodes
with an effect the description lacks) through the verbs that read a bag alone: the README's
table of hidden effects is the oracle (each bag diagnoses to its documented effect, parameters
within 10 %), ``cablelab report`` renders from the bag alone and ranks that effect first, and
``cablelab batch`` over a folder of two mjcf bags writes its table and index with both."""
from __future__ import annotations

import html
import json
import re
import shutil
import subprocess
import sys
from pathlib import Path

import pytest

import cablelab

PLANT = Path(cablelab.__file__).resolve().parent / "plants" / "mjcf"
DATA = PLANT / "data"
ROW = re.compile(r"^\| `(\w+)` \| `([\w.]+)` \| [^|]+ \| `(\w+)` \| (.+) \|$")
PARAM = re.compile(r"`([^`]+)` = ([-\d.]+)")


def readme_claims() -> dict:
    """``bag -> (example file, effect id, {param: value})`` from the README's table of shipped
    bags (the documented claim, independent of the code that made or analyses the bags)."""
    text = (PLANT / "README.md").read_text(encoding="utf-8")
    section = text.split("## Shipped bags", 1)[1].split("\n## ", 1)[0]
    claims = {}
    for line in section.splitlines():
        m = ROW.match(line.strip())
        if m:
            claims[m[1]] = (m[2], m[3], {k: float(v) for k, v in PARAM.findall(m[4])})
    return claims


CLAIMS = readme_claims()


def _cli(*args, timeout=600):
    p = subprocess.run([sys.executable, "-m", "cablelab.cli", *map(str, args)], capture_output=True,
                       text=True, timeout=timeout)
    assert p.returncode == 0, p.stderr[-3000:]
    return p


def _copy(name, dst: Path) -> Path:
    """The shipped bag alone, away from the repository's descriptions and examples."""
    shutil.copytree(DATA / name, dst / name)
    return dst / name


def test_readme_documents_every_shipped_bag():
    """Three bags, one per example, each a rosbag2 directory of a few hundred kB at most, and
    the demo part's table says the same as the README."""
    from cablelab.plants.mjcf.demo import SHIPPED

    shipped = sorted(p.name for p in DATA.iterdir() if (p / "metadata.yaml").is_file())
    assert shipped == sorted(CLAIMS) and len(shipped) == 3
    assert sorted(e for e, _, _ in CLAIMS.values()) == ["arm3.xml", "cablecam.xml", "gantry.xml"]
    for name in shipped:
        files = sorted(f.name for f in (DATA / name).iterdir())
        assert files == sorted([f"{name}.mcap", "metadata.yaml"]), files
        assert sum(f.stat().st_size for f in (DATA / name).iterdir()) < 700_000
        _, effect, params = CLAIMS[name]
        assert (SHIPPED[name].effect, SHIPPED[name].params) == (effect, params)


@pytest.mark.parametrize("name", sorted(CLAIMS))
def test_shipped_bag_diagnoses_to_its_documented_hidden_effect(name, tmp_path):
    """``cablelab diagnose --json`` on the bag alone: the README's effect ranks first and
    significant; ``identify`` with it gives the README's parameters within 10 %. The bag's
    description is the example as shipped (the hidden effect is only in the simulator)."""
    from cablelab.bags import open_bag
    from cablelab.plants.mjcf.examples import HERE

    example, effect, params = CLAIMS[name]
    bag = _copy(name, tmp_path)
    assert open_bag(bag).description.mjcf.model.strip() == (HERE / example).read_text().strip()
    d = json.loads(_cli("diagnose", bag, "--json").stdout)
    top = d["ranking"][0]
    assert top["effect"] == effect and top["significant"], d["ranking"][:2]
    ident = json.loads(_cli("identify", bag, "--effects", effect, "--json").stdout)
    for k, v in params.items():
        assert ident["params"][k]["value"] == pytest.approx(v, rel=0.10), (k, ident["params"][k])


def test_report_renders_from_the_bag_alone_and_ranks_the_hidden_effect_first(tmp_path):
    """``cablelab report`` of the gantry bag copied alone to a temporary folder (the model XML
    travels in /plant_description): index.html and its overlay bag, and the ranking table's first
    row is the README's hidden effect, marked significant."""
    name = "gantry_friction"
    bag = _copy(name, tmp_path)
    out = tmp_path / "report"
    _cli("report", bag, "-o", out)
    page = (out / "index.html").read_text(encoding="utf-8")
    assert "<title>cablelab report</title>" in page
    ranking = page.split("Ranking of the candidate effects", 1)[1]
    first_row = ranking.split("<tr>", 3)[2]          # [0] before the table, [1] the heading row
    first_cell = re.search(r"<td>(.*?)</td>", first_row, re.S)[1]
    assert "class='sig'" in first_cell
    assert html.unescape(re.sub(r"<[^>]+>", "", first_cell)) == CLAIMS[name][1]
    assert list((out / "overlay").glob("*.mcap"))


def test_batch_over_two_mjcf_bags_writes_table_and_index_with_both(tmp_path):
    """``cablelab batch`` over a folder holding the arm and the cable camera bags: results.parquet
    has an ``ok`` row per bag with the mjcf plant and each bag's documented effect significant;
    the fleet index lists both bags."""
    import pyarrow.parquet as pq

    root = tmp_path / "fleet"
    root.mkdir()
    names = ["arm3_payload", "cablecam_payload"]
    for n in names:
        _copy(n, root)
    out = tmp_path / "out"
    summary = json.loads(_cli("batch", root, "-o", out, "--workers", "1", "--json").stdout)
    assert summary["bags"] == 2 and summary["failed"] == 0, summary
    rows = pq.read_table(out / "results.parquet").to_pylist()
    assert {r["status"] for r in rows} == {"ok"}
    assert {r["plant"] for r in rows} == {"mjcf"}
    for n in names:
        mine = [r for r in rows if r["bag"].split("/")[0] == n or n in r["bag"]]
        assert mine, (n, sorted({r["bag"] for r in rows}))
        hit = [r for r in mine if r["effect"] == CLAIMS[n][1]]
        assert hit and hit[0]["significant"], [(r["effect"], r["significant"]) for r in mine]
    index = (out / "index.html").read_text(encoding="utf-8")
    for n in names:
        assert n in index


def test_demo_part_on_the_arm_bag_links_what_it_names(tmp_path):
    """The mjcf part of ``./run demo`` on the shipped arm bag: the diagnosis names the README's
    effect first, the identified mass is within 10 % of the README's, and the demo index built
    from the part links its page, its ``cablelab report`` and its bag as the other parts do
    (``check_index_links`` of test/core/test_demo.py)."""
    import argparse
    import importlib.util

    from cablelab import demo
    from cablelab.plants.mjcf.demo import DEMO

    spec = importlib.util.spec_from_file_location(
        "demo_index_links", Path(__file__).resolve().parents[2] / "core" / "test_demo.py")
    links = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(links)
    a = argparse.Namespace(mjcf_bags="arm3_payload", folds=3, quick=True)
    out = tmp_path / "mjcf"
    res = DEMO.analyse(out, a, DEMO.record(out, a))
    _, effect, params = CLAIMS["arm3_payload"]
    assert res.first == effect
    identified = dict(r[:2] for r in res.rows)["arm3_payload: identified"]
    m = float(re.match(r"m = ([-\d.]+)", identified)[1])
    assert m == pytest.approx(params["m"], rel=0.10)
    index = demo.index_page(tmp_path, {DEMO.title: res})
    kinds = {text.split()[0] for _, text in links.check_index_links(index)}
    assert kinds == {"demo", "diagnosis", "bag"}
